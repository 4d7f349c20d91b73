// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <string>

#include "codec/format.hpp"
#include "pointset/octree.hpp"
#include "quant/scalar_quantizer.hpp"
#include "util/bytes.hpp"
#include "util/error.hpp"

namespace hmc {

namespace {

using namespace detail;

void check_connectivity(const Mesh& m) {
  const auto n = m.points.size();
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    for (auto v : m.triangles[i])
      if (v >= n)
        fail(Status::invalid_argument, "triangle " + std::to_string(i) + " uses vertex " + std::to_string(v) +
                                           ", there are " + std::to_string(n));
  for (std::size_t i = 0; i < m.tetrahedra.size(); ++i)
    for (auto v : m.tetrahedra[i])
      if (v >= n)
        fail(Status::invalid_argument, "tetrahedron " + std::to_string(i) + " uses vertex " + std::to_string(v) +
                                           ", there are " + std::to_string(n));
}

Kind detect_kind(const Mesh& m) {
  if (!m.tetrahedra.empty()) return Kind::volume;
  if (!m.triangles.empty()) return Kind::surface;
  return Kind::points;
}

std::vector<std::uint8_t> info_payload(const EncodeReport& r) {
  std::string s = std::string("encoder=hmc ") + version_string() + "\n";
  s += "input_points=" + std::to_string(r.input_points) + "\n";
  s += "duplicates_merged=" + std::to_string(r.duplicates_merged) + "\n";
  return {s.begin(), s.end()};
}

Encoded encode_impl(const Mesh& input, const EncodeOptions& options) {
  check_connectivity(input);
  Encoded out;
  EncodeReport& rep = out.report;
  rep.kind = options.kind ? *options.kind : detect_kind(input);
  if (static_cast<int>(rep.kind) > 2) fail(Status::invalid_argument, "unknown kind");
  rep.quantizer = fit_quantizer(input.points, options.bits);
  out.points = quantize(input.points, rep.quantizer);
  sort_canonical(out.points);
  out.points.erase(std::unique(out.points.begin(), out.points.end()), out.points.end());
  rep.input_points = input.points.size();
  rep.distinct_points = out.points.size();
  rep.duplicates_merged = rep.input_points - rep.distinct_points;

  Header header;
  header.kind = rep.kind;
  header.points = {rep.distinct_points};

  ContainerWriter w;
  w.chunk(kHead, header.write());
  w.chunk(kScalarQuantizer, write_scalar_quantizer(rep.quantizer));
  if (options.write_info) w.chunk(kInfo, info_payload(rep));

  const std::size_t before = w.size();
  ByteWriter base;
  base.u8(static_cast<std::uint8_t>(BaseCoder::octree));
  base.bytes(encode_octree(out.points, rep.quantizer.bits));
  w.chunk(kBaseLayer, base.data());
  LevelReport level;
  level.lod = 0;
  level.points = level.new_points = rep.distinct_points;
  level.layer_bytes = w.size() - before;
  level.stream_bytes = w.size();
  rep.levels.push_back(level);

  w.chunk(kEnd, {});
  out.bytes = w.finish();
  rep.total_bytes = out.bytes.size();
  return out;
}

}  // namespace

const char* kind_name(Kind k) noexcept {
  switch (k) {
    case Kind::points: return "points";
    case Kind::surface: return "surface";
    case Kind::volume: return "volume";
  }
  return "unknown";
}

const char* version_string() noexcept { return HMC_VERSION_STRING; }

Result<Encoded> encode(const Mesh& input, const EncodeOptions& options) {
  return guarded<Result<Encoded>>([&] { return Result<Encoded>(encode_impl(input, options)); });
}

}  // namespace hmc
