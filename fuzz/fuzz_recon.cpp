// SPDX-License-Identifier: AGPL-3.0-or-later
// Fuzz target: reconstruction side information (RCON) and the normative
// reconstruction it drives, on a small point set taken from the input.
//
// Input: u8 kind (surface or volume), u8 point count p (4..40), p points of
// 3 x u8 (a 2^8 grid), then an RCON payload. Checks: read_recon raises only
// bad_layer / bad_huffman_table; a payload that parses writes back to the
// same parameters; reconstruction raises only bad_layer (out-of-range
// toggles or drops) and its output indexes the points.
#include <algorithm>
#include <vector>

#include "codec/format.hpp"
#include "delaunay/delaunay.hpp"
#include "fuzz_check.hpp"
#include "reconstruct/reconstruct.hpp"
#include "util/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hmc_fuzz::Params params(data, size);
  const hmc::Kind kind = params.u8() & 1 ? hmc::Kind::volume : hmc::Kind::surface;
  const int p = 4 + params.u8() % 37;
  std::vector<hmc::GridPoint> points;
  for (int i = 0; i < p; ++i) points.push_back({params.u8(), params.u8(), params.u8()});
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());

  hmc::detail::ChunkView c;
  c.type = hmc::detail::kRecon;
  c.payload = params.rest();
  c.length = static_cast<std::uint32_t>(params.rest_size());
  hmc::detail::ReconParams rp;
  try {
    rp = hmc::detail::read_recon(c, points.size());
  } catch (const hmc::detail::StreamError& e) {
    const hmc::Status s = e.error().status;
    FUZZ_CHECK(s == hmc::Status::bad_layer || s == hmc::Status::bad_huffman_table, "read_recon raised %s: %s",
               hmc::status_name(s), e.what());
    return 0;
  }
  const auto bytes = hmc::detail::write_recon(rp);
  hmc::detail::ChunkView again = c;
  again.payload = bytes.data();
  again.length = static_cast<std::uint32_t>(bytes.size());
  const auto back = hmc::detail::read_recon(again, points.size());
  FUZZ_CHECK(back.multipliers == rp.multipliers && back.vertex_class == rp.vertex_class && back.compact == rp.compact &&
                 back.candidate_contexts == rp.candidate_contexts && back.vertex_contexts == rp.vertex_contexts &&
                 back.neighbour_contexts == rp.neighbour_contexts && back.neighbour_lists == rp.neighbour_lists &&
                 back.neighbour_inverted == rp.neighbour_inverted && back.toggles == rp.toggles &&
                 back.toggle_ranks == rp.toggle_ranks && back.drops == rp.drops && back.border == rp.border &&
                 back.filters == rp.filters && back.peel == rp.peel && back.repair == rp.repair &&
                 back.scale_rank == rp.scale_rank && back.border_delta == rp.border_delta,
             "RCON does not survive a write and a read");

  // A lone level inherits the empty border (flag bit 3).
  hmc::detail::resolve_border(rp, {});
  const auto dt = hmc::detail::delaunay(points);
  hmc::detail::Reconstruction rec;
  try {
    rec = hmc::detail::reconstruct(points, dt, kind, rp);
  } catch (const hmc::detail::StreamError& e) {
    FUZZ_CHECK(e.error().status == hmc::Status::bad_layer, "reconstruct raised %s: %s",
               hmc::status_name(e.error().status), e.what());
    return 0;
  }
  for (const auto& t : rec.triangles)
    for (auto v : t) FUZZ_CHECK(v < points.size(), "triangle vertex %u out of range", v);
  for (const auto& t : rec.tetrahedra)
    for (auto v : t) FUZZ_CHECK(v < points.size(), "tetrahedron vertex %u out of range", v);
  return 0;
}
