// SPDX-License-Identifier: AGPL-3.0-or-later
// The chunks HMC defines and the syntax of the header and quantizer tables
// (spec "Chunks", "Header", "Scalar-quantizer table", "Vector-quantizer
// table"). Each field is declared once here and used to both read and write.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "codec/coders.hpp"
#include "container/container.hpp"
#include "entropy/huffman.hpp"
#include "hmc/codec.hpp"
#include "reconstruct/reconstruct.hpp"

namespace hmc::detail {

inline constexpr ChunkType kHead = chunk_type("HEAD");
inline constexpr ChunkType kScalarQuantizer = chunk_type("SQNT");
inline constexpr ChunkType kBaseLayer = chunk_type("BASE");
inline constexpr ChunkType kRecon = chunk_type("RCON");
inline constexpr ChunkType kRefinement = chunk_type("REFN");
inline constexpr ChunkType kEnd = chunk_type("HEND");
inline constexpr ChunkType kInfo = chunk_type("info");

/// True for the chunk types this version defines.
bool is_known_chunk(const ChunkType& t);

constexpr int kMinBits = 1;
constexpr int kMaxBits = 21;
constexpr std::uint32_t kMaxLevels = 64;

/// HEAD: kind, reserved flags, level count and per-level point counts.
struct Header {
  Kind kind = Kind::points;
  std::vector<std::uint64_t> points;  ///< cumulative point count per level, coarsest first
  /// Flag bit 0 (spec 0.10): every code-length table of the stream uses the
  /// delta form of spec 7.1; without it, the 4-bit form.
  TableForm tables = TableForm::deltas;

  std::vector<std::uint8_t> write() const;
  static Header read(const ChunkView& c, const DecodeLimits& limits);
};

std::vector<std::uint8_t> write_scalar_quantizer(const ScalarQuantizer& q);
ScalarQuantizer read_scalar_quantizer(const ChunkView& c);

/// RCON: reconstruction side information of one level with `points` points.
std::vector<std::uint8_t> write_recon(const ReconParams& p);
ReconParams read_recon(const ChunkView& c, std::uint64_t points, TableForm form = TableForm::deltas);

constexpr std::uint32_t kMaxClasses = 64;
constexpr std::uint32_t kMaxScaleRank = 64;

}  // namespace hmc::detail
