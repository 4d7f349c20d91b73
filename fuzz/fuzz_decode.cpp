// SPDX-License-Identifier: AGPL-3.0-or-later
// Fuzz target: the public decoder (hmc::decode) and hmc::inspect on the
// whole input, with tight limits.
//
// The input is decoded twice: as it is, and with the CRC of every complete
// chunk recomputed, so that mutated payloads get past the CRC check and
// reach the header, table and layer parsers.
//
// Decoding skips the reconstruction of triangles or tetrahedra (where the
// library has it) except for sets of at most kMaxReconstruct points, which
// are decoded again with it: the Delaunay step costs far more per point
// than the point decoding fuzzed here.
//
// Checks: every failure is one of the spec's stream error classes; a
// decoded stream has its declared number of distinct grid points in
// canonical order; inspect agrees with decode (it succeeds whenever decode
// does, with the same header, quantizer and truncation, and decode fails
// whenever inspect does); with reconstruction, rebuilding only the finest
// level gives it the same elements, and decoding on two threads (each
// level's reconstruction beside the next level's decoding; with the finest
// level alone rebuilt, the coarser levels tetrahedralized ahead) gives the
// same result or the same error.
#include <cstring>
#include <vector>

#include "container/container.hpp"
#include "fuzz_check.hpp"
#include "hmc/codec.hpp"

namespace {

using hmc::GridPoint;
using hmc::Status;

bool less(const GridPoint& a, const GridPoint& b) {
  return a[0] != b[0] ? a[0] < b[0] : a[1] != b[1] ? a[1] < b[1] : a[2] < b[2];
}

constexpr std::size_t kMaxReconstruct = 2048;

bool same_quantizer(const hmc::ScalarQuantizer& a, const hmc::ScalarQuantizer& b) {
  return a.bits == b.bits && std::memcmp(a.origin.data(), b.origin.data(), sizeof a.origin) == 0 &&
         std::memcmp(&a.step, &b.step, sizeof a.step) == 0;
}

/// Recomputes the CRC of every complete chunk; false if none changed.
bool repair_crcs(std::vector<std::uint8_t>& s) {
  bool changed = false;
  std::size_t pos = hmc::detail::kPreambleSize;
  while (s.size() >= 8 && pos <= s.size() - 8) {
    const std::uint32_t len = s[pos + 4] | (std::uint32_t{s[pos + 5]} << 8) | (std::uint32_t{s[pos + 6]} << 16) |
                              (std::uint32_t{s[pos + 7]} << 24);
    if (std::uint64_t{len} + 12 > s.size() - pos) break;
    hmc::detail::ChunkType type;
    std::memcpy(type.data(), &s[pos], 4);
    const std::uint32_t crc = hmc::detail::chunk_crc(type, &s[pos + 8], len);
    for (int i = 0; i < 4; ++i) {
      const auto b = static_cast<std::uint8_t>(crc >> (8 * i));
      std::uint8_t& at = s[pos + 8 + len + static_cast<std::size_t>(i)];
      changed |= at != b;
      at = b;
    }
    pos += 12 + std::size_t{len};
  }
  return changed;
}

void check_stream(const std::uint8_t* data, std::size_t size) {
  hmc::DecodeOptions options;
  // 2^18 points: the largest streams (single-symbol octree codes declaring
  // the limit) decode in well under a second with the sanitizers.
  options.limits.max_points = std::uint64_t{1} << 18;
  options.limits.max_levels = 64;
  options.limits.max_bytes = std::uint64_t{1} << 24;
  // 16 MiB: at most about 100,000 tetrahedra, however the points lie (the
  // sets reconstructed here have at most 2,048 points, some 14,000
  // tetrahedra when they lie on a surface or in a volume).
  options.limits.max_memory = std::uint64_t{1} << 24;
  const bool can_reconstruct = hmc_fuzz::set_reconstruct(options, false);

  const auto dec = hmc::decode(data, size, options);
  const auto info = hmc::inspect(data, size, options.limits);

  if (!info.ok()) {
    FUZZ_CHECK(hmc_fuzz::is_stream_error(info.status()), "inspect: %s", info.error().to_string().c_str());
    FUZZ_CHECK(!dec.ok(), "decode succeeds where inspect fails with %s", info.error().to_string().c_str());
  }
  if (!dec.ok()) {
    FUZZ_CHECK(hmc_fuzz::is_stream_error(dec.status()), "decode: %s", dec.error().to_string().c_str());
    FUZZ_CHECK(!dec.error().message.empty(), "decode error without a message");
    return;
  }

  const hmc::Decoded& d = dec.value();
  FUZZ_CHECK(!d.levels.empty(), "decode succeeded without a level");
  FUZZ_CHECK(d.quantizer.bits >= 1 && d.quantizer.bits <= 21, "q = %d", d.quantizer.bits);
  FUZZ_CHECK(!d.declared_points.empty() && d.declared_points.size() <= 64, "%zu declared levels",
             d.declared_points.size());
  FUZZ_CHECK(d.declared_points.back() <= options.limits.max_points, "declared points over the limit");
  for (std::size_t i = 1; i < d.declared_points.size(); ++i)
    FUZZ_CHECK(d.declared_points[i - 1] < d.declared_points[i], "declared counts not increasing");
  FUZZ_CHECK(d.truncated == (d.levels.back().lod > 0), "truncated flag %d with finest decoded level %d",
             int(d.truncated), d.levels.back().lod);
  FUZZ_CHECK(!d.warning.empty() || d.levels.size() == d.declared_points.size(),
             "%zu of %zu levels decoded without a warning", d.levels.size(), d.declared_points.size());

  const std::uint32_t cells = d.quantizer.cells();
  for (std::size_t k = 0; k < d.levels.size(); ++k) {
    const hmc::DecodedLevel& level = d.levels[k];
    FUZZ_CHECK(level.lod == d.level_count() - 1 - static_cast<int>(k), "level %zu has lod %d", k, level.lod);
    FUZZ_CHECK(level.points.size() == d.declared_points[k], "level %zu: %zu points, %llu declared", k,
               level.points.size(), static_cast<unsigned long long>(d.declared_points[k]));
    FUZZ_CHECK(level.stream_bytes <= size, "level %zu ends at %llu, past the %zu-byte stream", k,
               static_cast<unsigned long long>(level.stream_bytes), size);
    for (std::size_t i = 0; i < level.points.size(); ++i) {
      const GridPoint& p = level.points[i];
      FUZZ_CHECK(p[0] < cells && p[1] < cells && p[2] < cells, "point %zu is outside the 2^%d grid", i,
                 d.quantizer.bits);
      FUZZ_CHECK(i == 0 || less(level.points[i - 1], p), "points %zu, %zu not in strict canonical order", i - 1, i);
    }
    FUZZ_CHECK(hmc_fuzz::check_connectivity(level, level.points.size()) == 0,
               "connectivity rebuilt though reconstruction is off");
  }

  FUZZ_CHECK(info.ok(), "inspect fails (%s) where decode succeeds", info.error().to_string().c_str());
  const hmc::StreamInfo& s = info.value();
  FUZZ_CHECK(s.kind == d.kind, "inspect and decode disagree on the kind");
  FUZZ_CHECK(same_quantizer(s.quantizer, d.quantizer), "inspect and decode disagree on the quantizer");
  FUZZ_CHECK(s.declared_points == d.declared_points, "inspect and decode disagree on the declared points");
  FUZZ_CHECK(s.version_major == d.version_major && s.version_minor == d.version_minor, "versions disagree");
  FUZZ_CHECK(s.total_bytes == size, "inspect total_bytes %llu for %zu bytes",
             static_cast<unsigned long long>(s.total_bytes), size);
  FUZZ_CHECK(s.levels.size() >= d.levels.size(), "inspect lists %zu levels, decode decoded %zu", s.levels.size(),
             d.levels.size());
  for (std::size_t k = 0; k < d.levels.size(); ++k)
    FUZZ_CHECK(s.levels[k].lod == d.levels[k].lod && s.levels[k].stream_bytes == d.levels[k].stream_bytes &&
                   s.levels[k].points == d.levels[k].points.size(),
               "inspect and decode disagree on level %zu", k);
  FUZZ_CHECK(s.truncated == !d.warning.empty(), "inspect truncated %d, decode warning '%s'", int(s.truncated),
             d.warning.c_str());
  FUZZ_CHECK(!s.chunks.empty() && s.chunks.front().type == "HEAD", "inspect's first chunk is not HEAD");

  // Small sets again, with reconstruction: the same points, and elements
  // that index them.
  if (can_reconstruct && d.finest().points.size() <= kMaxReconstruct) {
    hmc_fuzz::set_reconstruct(options, true);
    const auto full = hmc::decode(data, size, options);
    {
      hmc::DecodeOptions two = options;
      two.threads = 2;
      const auto t = hmc::decode(data, size, two);
      FUZZ_CHECK(t.ok() == full.ok(), "two threads: %s, one thread: %s", t.ok() ? "ok" : t.error().to_string().c_str(),
                 full.ok() ? "ok" : full.error().to_string().c_str());
      if (!t.ok()) {
        FUZZ_CHECK(t.error().to_string() == full.error().to_string(), "two threads: %s, one thread: %s",
                   t.error().to_string().c_str(), full.error().to_string().c_str());
      } else {
        FUZZ_CHECK(t.value().levels.size() == full.value().levels.size(), "two threads: other levels");
        for (std::size_t k = 0; k < t.value().levels.size(); ++k) {
          const hmc::DecodedLevel &x = t.value().levels[k], &y = full.value().levels[k];
          FUZZ_CHECK(x.points == y.points && x.triangles == y.triangles && x.tetrahedra == y.tetrahedra &&
                         x.rebuilt == y.rebuilt,
                     "two threads: level %zu differs", k);
        }
      }
    }
    // Only a reconstructing decoder checks some side information (toggle
    // indices against the tetrahedra, spec "RCON") and builds a
    // tetrahedralization, which may exceed the memory limit (points on two
    // skew lines): those errors may appear here, nothing else.
    if (!full.ok()) {
      FUZZ_CHECK(full.status() == Status::bad_layer || full.status() == Status::limit_exceeded,
                 "decoding with reconstruction: %s", full.error().to_string().c_str());
      return;
    }
    const hmc::Decoded& f = full.value();
    FUZZ_CHECK(f.levels.size() == d.levels.size(), "reconstruction changes the levels decoded");
    for (std::size_t k = 0; k < f.levels.size(); ++k) {
      FUZZ_CHECK(f.levels[k].points == d.levels[k].points, "reconstruction changes the points of level %zu", k);
      const std::size_t elements = hmc_fuzz::check_connectivity(f.levels[k], f.levels[k].points.size());
      if (f.kind == hmc::Kind::points) FUZZ_CHECK(elements == 0, "elements rebuilt for kind points");
    }
    // The finest decoded level alone rebuilt: the same levels and points,
    // the same elements for that level, none for the others.
    options.rebuild_coarser_levels = false;
    const auto fin = hmc::decode(data, size, options);
    FUZZ_CHECK(fin.ok(), "rebuilding the finest level alone fails: %s", fin.error().to_string().c_str());
    const hmc::Decoded& g = fin.value();
    FUZZ_CHECK(g.levels.size() == f.levels.size(), "rebuilding the finest level alone changes the levels decoded");
    for (std::size_t k = 0; k < g.levels.size(); ++k) {
      const bool last = k + 1 == g.levels.size();
      FUZZ_CHECK(g.levels[k].points == f.levels[k].points, "level %zu: other points when rebuilt alone", k);
      FUZZ_CHECK(g.levels[k].triangles == (last ? f.levels[k].triangles : std::vector<hmc::Triangle>{}) &&
                     g.levels[k].tetrahedra == (last ? f.levels[k].tetrahedra : std::vector<hmc::Tetrahedron>{}),
                 "level %zu: other elements when only the finest level is rebuilt", k);
    }
    // The same on two threads (the coarser levels tetrahedralized ahead,
    // speculatively, the finest one's refined from them): what one thread
    // decodes, two decode the same.
    hmc::DecodeOptions two = options;
    two.threads = 2;
    const auto fin2 = hmc::decode(data, size, two);
    FUZZ_CHECK(fin2.ok(), "the finest level alone on two threads fails: %s", fin2.error().to_string().c_str());
    FUZZ_CHECK(fin2.value().levels.size() == g.levels.size(), "the finest level alone on two threads: other levels");
    for (std::size_t k = 0; k < g.levels.size(); ++k) {
      const hmc::DecodedLevel &x = fin2.value().levels[k], &y = g.levels[k];
      FUZZ_CHECK(x.points == y.points && x.triangles == y.triangles && x.tetrahedra == y.tetrahedra &&
                     x.rebuilt == y.rebuilt,
                 "the finest level alone on two threads: level %zu differs", k);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  check_stream(data, size);
  std::vector<std::uint8_t> repaired(data, data + size);
  if (repair_crcs(repaired)) check_stream(repaired.data(), repaired.size());
  return 0;
}
