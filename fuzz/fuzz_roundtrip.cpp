// SPDX-License-Identifier: AGPL-3.0-or-later
// Fuzz target: encode then decode a point set built from the input.
//
// Input: u8 q (mapped to 1..21); u8 flags (bits 0-1: kind points, surface,
// volume or automatic; bit 2: write the info chunk; bits 3-4: how the
// coordinates are read, see `coordinate`); u8 permutation seed; then 12
// bytes per point, 4 per coordinate (at most 4096 points).
//
// Checks: the encoder fails exactly on empty input and non-finite
// coordinates; otherwise the decoded set is the set of distinct quantized
// points, computed here from the spec's description of the reference
// quantizer (origin = box minimum, step = largest extent / (2^q - 1),
// rounding halves up); each input point lies within half a step of its
// grid point; the stream and report are the same for a permutation of the
// input encoded on two threads; decode and inspect agree with the encoder's report, and the
// decoder rebuilds the connectivity the encoder predicted (surface and
// volume kinds, sets of at most 256 points).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "fuzz_check.hpp"
#include "hmc/codec.hpp"

namespace {

using hmc::GridPoint;
using hmc::Status;
using hmc::Vec3;

constexpr std::size_t kMaxPoints = 4096;
// Surface and volume kinds make the encoder and decoder rebuild connectivity
// (a Delaunay tetrahedralization and its labelling, where the library has
// them), far slower per point: those kinds are used for small sets only.
constexpr std::size_t kMaxPointsWithConnectivity = 256;

double coordinate(const std::uint8_t* p, unsigned mode) {
  const std::uint32_t u = p[0] | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) |
                          (std::uint32_t{p[3]} << 24);
  std::int32_t i;
  std::memcpy(&i, &u, 4);
  switch (mode) {
    case 0: return static_cast<double>(i);                    // integers, full range
    case 1: {                                                 // any float, NaN and infinities too
      float f;
      std::memcpy(&f, &u, 4);
      return static_cast<double>(f);
    }
    case 2: return static_cast<double>(i / (1 << 20));        // small integers: many duplicates
    default: return std::ldexp(static_cast<double>(i), -30);  // fractions: halfway cases
  }
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

struct Expected {
  bool valid = true;
  hmc::ScalarQuantizer quantizer;
  std::vector<GridPoint> grid;      // per input point
  std::vector<GridPoint> distinct;  // sorted, unique
};

Expected expected_encoding(const std::vector<Vec3>& pts, int q) {
  Expected e;
  if (pts.empty()) {
    e.valid = false;
    return e;
  }
  Vec3 lo = pts[0], hi = pts[0];
  for (const Vec3& p : pts)
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(p[a])) {
        e.valid = false;
        return e;
      }
      lo[a] = p[a] < lo[a] ? p[a] : lo[a];
      hi[a] = p[a] > hi[a] ? p[a] : hi[a];
    }
  // The box minimum; a zero minimum is +0.0 whichever signed zero came
  // first (the stream must not depend on the input order).
  for (double& o : lo)
    if (o == 0) o = 0.0;
  double extent = 0;
  for (int a = 0; a < 3; ++a) extent = std::max(extent, hi[a] - lo[a]);
  const double top = static_cast<double>((std::uint32_t{1} << q) - 1);
  e.quantizer.bits = q;
  e.quantizer.origin = lo;
  e.quantizer.step = extent > 0 ? extent / top : 1.0;
  if (!std::isfinite(extent) || !(e.quantizer.step > 0) || !std::isfinite(e.quantizer.step)) {
    e.valid = false;
    return e;
  }
  for (const Vec3& p : pts) {
    GridPoint g;
    for (int a = 0; a < 3; ++a) {
      const double t = (p[a] - lo[a]) / e.quantizer.step;
      double r = std::floor(t);
      if (t - r >= 0.5) r += 1;  // halves up; t - floor(t) is exact
      g[a] = static_cast<std::uint32_t>(std::min(std::max(r, 0.0), top));
    }
    e.grid.push_back(g);
  }
  e.distinct = e.grid;
  std::sort(e.distinct.begin(), e.distinct.end());
  e.distinct.erase(std::unique(e.distinct.begin(), e.distinct.end()), e.distinct.end());
  return e;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hmc_fuzz::Params params(data, size);
  const int q = 1 + params.u8() % 21;
  const unsigned flags = params.u8();
  std::uint32_t seed = params.u8();

  hmc::Mesh mesh;
  const std::uint8_t* rec = params.rest();
  for (std::size_t i = 0; i + 12 <= params.rest_size() && mesh.points.size() < kMaxPoints; i += 12)
    mesh.points.push_back({coordinate(rec + i, (flags >> 3) & 3), coordinate(rec + i + 4, (flags >> 3) & 3),
                           coordinate(rec + i + 8, (flags >> 3) & 3)});

  hmc::EncodeOptions opt;
  opt.bits = q;
  if ((flags & 3) != 3) opt.kind = static_cast<hmc::Kind>(flags & 3);
  if (mesh.points.size() > kMaxPointsWithConnectivity) opt.kind = hmc::Kind::points;
  opt.write_info = (flags & 4) != 0;
  const hmc::Kind kind = opt.kind ? *opt.kind : hmc::Kind::points;

  const Expected want = expected_encoding(mesh.points, q);
  auto enc = hmc::encode(mesh, opt);
  if (!want.valid) {
    FUZZ_CHECK(!enc.ok() && enc.status() == Status::invalid_argument,
               "encoding %zu points with non-finite or no coordinates gives %s", mesh.points.size(),
               enc.ok() ? "ok" : enc.error().to_string().c_str());
    return 0;
  }
  FUZZ_CHECK(enc.ok(), "encode: %s", enc.error().to_string().c_str());
  const hmc::Encoded& e = enc.value();
  const hmc::EncodeReport& rep = e.report;
  FUZZ_CHECK(rep.quantizer.bits == q && same_bits(rep.quantizer.step, want.quantizer.step) &&
                 same_bits(rep.quantizer.origin[0], want.quantizer.origin[0]) &&
                 same_bits(rep.quantizer.origin[1], want.quantizer.origin[1]) &&
                 same_bits(rep.quantizer.origin[2], want.quantizer.origin[2]),
             "quantizer (step %.17g) differs from the reference (step %.17g)", rep.quantizer.step,
             want.quantizer.step);
  FUZZ_CHECK(e.points == want.distinct, "encoder's points: %zu, expected %zu distinct", e.points.size(),
             want.distinct.size());
  FUZZ_CHECK(rep.kind == kind, "kind %d, asked for %d", int(rep.kind), int(kind));
  FUZZ_CHECK(rep.input_points == mesh.points.size() && rep.distinct_points == want.distinct.size() &&
                 rep.duplicates_merged == mesh.points.size() - want.distinct.size(),
             "report counts are wrong");
  FUZZ_CHECK(rep.total_bytes == e.bytes.size(), "report total_bytes is wrong");
  FUZZ_CHECK(rep.levels.size() == 1 && rep.levels[0].points == want.distinct.size() &&
                 rep.levels[0].stream_bytes + 12 == e.bytes.size(),  // then HEND
             "report levels are wrong");

  // Each input point is within half a step (plus rounding) of its grid point.
  const double step = want.quantizer.step;
  for (std::size_t i = 0; i < mesh.points.size(); ++i) {
    const Vec3 back = rep.quantizer.dequantize(want.grid[i]);
    for (int a = 0; a < 3; ++a) {
      const double c = mesh.points[i][a];
      const double slack = 1e-12 * (std::fabs(c) + std::fabs(want.quantizer.origin[a]) +
                                    step * static_cast<double>(rep.quantizer.cells()));
      FUZZ_CHECK(std::fabs(back[a] - c) <= 0.5 * step + slack, "point %zu axis %d: %.17g quantizes to %.17g", i, a,
                 c, back[a]);
    }
  }

  // Decoding gives the set back.
  const auto dec = hmc::decode(e.bytes.data(), e.bytes.size());
  FUZZ_CHECK(dec.ok(), "decoding an encoded stream: %s", dec.error().to_string().c_str());
  const hmc::Decoded& d = dec.value();
  FUZZ_CHECK(!d.truncated && d.warning.empty(), "a complete stream decodes as truncated: %s", d.warning.c_str());
  FUZZ_CHECK(d.levels.size() == 1 && d.finest().points == want.distinct, "decoded %zu points, expected %zu",
             d.levels.empty() ? std::size_t{0} : d.finest().points.size(), want.distinct.size());
  FUZZ_CHECK(d.kind == kind, "decoded kind %d, encoded %d", int(d.kind), int(kind));
  FUZZ_CHECK(d.quantizer.bits == q && same_bits(d.quantizer.step, step) &&
                 same_bits(d.quantizer.origin[0], want.quantizer.origin[0]) &&
                 same_bits(d.quantizer.origin[1], want.quantizer.origin[1]) &&
                 same_bits(d.quantizer.origin[2], want.quantizer.origin[2]),
             "decoded quantizer differs");
  FUZZ_CHECK(d.info.empty() != opt.write_info, "info chunk %s", opt.write_info ? "missing" : "unexpected");

  // The connectivity the encoder predicts is what the decoder rebuilds.
  hmc_fuzz::check_connectivity(e, e.points.size());
  FUZZ_CHECK(hmc_fuzz::same_connectivity(e, d.finest()), "decoded connectivity differs from the encoder's");
  if (kind == hmc::Kind::points)
    FUZZ_CHECK(hmc_fuzz::check_connectivity(d.finest(), d.finest().points.size()) == 0, "elements for kind points");

  const auto info = hmc::inspect(e.bytes.data(), e.bytes.size());
  FUZZ_CHECK(info.ok() && !info.value().truncated && info.value().levels.size() == 1 &&
                 info.value().levels[0].points == want.distinct.size() &&
                 info.value().levels[0].stream_bytes == rep.levels[0].stream_bytes,
             "inspect disagrees with the encoder");
  std::size_t info_chunks = 0;
  for (const auto& c : info.value().chunks) info_chunks += c.type == "info";
  FUZZ_CHECK(info_chunks == (opt.write_info ? 1u : 0u), "%zu info chunks", info_chunks);

  // The stream codes the set: permuting the input changes nothing, nor
  // does encoding on two threads (done here with the permuted input).
  if (mesh.points.size() > 1) {
    hmc::Mesh shuffled = mesh;
    std::reverse(shuffled.points.begin(), shuffled.points.end());
    for (std::size_t i = shuffled.points.size() - 1; i > 0; --i) {
      seed = seed * 1103515245u + 12345u;
      std::swap(shuffled.points[i], shuffled.points[(seed >> 8) % (i + 1)]);
    }
    hmc::EncodeOptions two = opt;
    two.threads = 2;
    const auto again = hmc::encode(shuffled, two);
    FUZZ_CHECK(again.ok(), "encoding the permuted input: %s", again.error().to_string().c_str());
    FUZZ_CHECK(again.value().bytes == e.bytes, "the stream depends on the order of the input points or the threads");
    FUZZ_CHECK(again.value().points == e.points, "the encoder's points depend on the input order");
  }
  return 0;
}
