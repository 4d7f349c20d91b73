// SPDX-License-Identifier: AGPL-3.0-or-later
// A tiled model (spec/tiles.md): its index, and its tiles decoded and merged
// by the border rule.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "cli.hpp"
#include "hmc/codec.hpp"

namespace hmc::cli {

struct TileEntry {
  std::string file;
  std::array<std::int64_t, 6> box{};     // half-open ownership box
  std::array<std::int64_t, 6> bounds{};  // closed box of the owned points
  std::uint64_t points = 0;              // owned at level 0
  int levels = 0;
  std::vector<std::uint64_t> stream_points, level_bytes;  // level 0 first
  std::uint64_t bytes = 0;
  std::uint32_t crc32 = 0;
};

struct TileIndex {
  std::string dir;
  Kind kind = Kind::points;
  ScalarQuantizer quantizer;
  std::int64_t margin = 0;
  int levels = 1;
  std::uint64_t points = 0;
  std::vector<TileEntry> tiles;
};

/// A directory holding tiles.json, or a path to a tiles.json.
bool is_tiled(const std::string& path);
/// Read and check the index (spec/tiles.md section 4).
Result<TileIndex> load_index(const std::string& path);

struct MergedLevel {
  int lod = 0;
  std::vector<GridPoint> points;  // canonical order
  std::vector<Triangle> triangles;
  std::vector<Tetrahedron> tetrahedra;
  std::size_t foreign_points = 0;  // vertices of kept simplices that no decoded tile owns at this level
  bool rebuilt = false;
};

struct Merged {
  std::vector<MergedLevel> levels;  // coarsest first
  std::size_t tiles_read = 0;
  std::uint64_t bytes_read = 0;
};

/// Decode tiles `which` down to `level` (and the coarser levels too with
/// all_levels) and merge them (spec/tiles.md section 5).
Result<Merged> decode_tiles(const TileIndex& ix, const std::vector<std::size_t>& which, int level, bool all_levels,
                            const DecodeOptions& base);
/// Tiles whose dequantized bounds meet the closed box xmin,ymin,zmin,xmax,ymax,zmax.
std::vector<std::size_t> tiles_in_region(const TileIndex& ix, const std::array<double, 6>& region);

/// `hmc dec TILED ...` and `hmc info TILED`.
int dec_tiled(Args& a, DecodeOptions opt);
int info_tiled(const std::string& in, bool json);

}  // namespace hmc::cli
