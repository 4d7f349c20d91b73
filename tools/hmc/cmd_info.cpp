// SPDX-License-Identifier: AGPL-3.0-or-later
#include <cstdio>
#include <string>

#include "cli.hpp"
#include "tiles.hpp"
#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"

namespace hmc::cli {

namespace {

// REFN coders (spec 8A).
const char* refinement_coder_name(int coder) {
  switch (coder) {
    case 0: return "conditional octree";
    case 7: return "conditional octree, full header";
    default: return "unknown";
  }
}

// BASE coders (spec 8).
const char* base_coder_name(int coder) {
  switch (coder) {
    case 0: return "octree";
    case 5: return "ranked octree";
    default: return "unknown";
  }
}

}  // namespace

int cmd_info(int argc, char** argv) {
  Args a(argc, argv, 2, {"--json"}, {});
  if (!a.ok() || a.positional().size() != 1) {
    std::fprintf(stderr, "hmc info: %s\nusage: hmc info IN.hmc [--json]\n", a.ok() ? "need one input stream" : a.error().c_str());
    return kUsage;
  }
  const std::string in = a.positional()[0];
  if (is_tiled(in)) return info_tiled(in, a.flag("--json"));  // spec/tiles.md
  DecodeLimits limits;
  auto bytes = io::read_file(in, limits.max_bytes);
  if (!bytes) return report("cannot read " + in, bytes.error(), Stage::input);
  const auto& b = bytes.value();
  auto res = inspect(reinterpret_cast<const std::uint8_t*>(b.data()), b.size(), limits);
  if (!res) return report(in, res.error(), Stage::input);
  const StreamInfo& s = res.value();
  // LevelReport::coder names REFN coders only; the base's is its payload's first byte.
  int base_coder = -1;
  for (const auto& c : s.chunks)
    if (c.type == "BASE" && c.length > 0) base_coder = static_cast<unsigned char>(b[c.offset + 8]);
  auto coder_name = [&](std::size_t i) {
    return i == 0 ? base_coder_name(base_coder) : refinement_coder_name(s.levels[i].coder);
  };
  if (a.flag("--json")) {
    Json j;
    j.begin_object();
    j.key("input").value(in);
    j.key("version").value(std::to_string(s.version_major) + "." + std::to_string(s.version_minor));
    j.key("kind").value(kind_name(s.kind)).key("q").value(s.quantizer.bits);
    j.key("origin").begin_array().value(s.quantizer.origin[0]).value(s.quantizer.origin[1]).value(s.quantizer.origin[2]).end_array();
    j.key("step").value(s.quantizer.step);
    j.key("bytes").value(s.total_bytes).key("truncated").value(s.truncated);
    if (s.truncated) j.key("warning").value(s.warning);
    j.key("chunks").begin_array();
    for (const auto& c : s.chunks) {
      j.begin_object();
      j.key("type").value(c.type).key("offset").value(c.offset).key("length").value(static_cast<std::uint64_t>(c.length));
      j.key("critical").value(c.critical).key("known").value(c.known);
      j.end_object();
    }
    j.end_array();
    j.key("levels").begin_array();
    for (std::size_t i = 0; i < s.levels.size(); ++i) {
      const auto& l = s.levels[i];
      j.begin_object();
      j.key("level").value(l.lod).key("points").value(l.points).key("new_points").value(l.new_points);
      j.key("layer_bytes").value(l.layer_bytes).key("stream_bytes").value(l.stream_bytes);
      j.key("coder").value(i == 0 ? base_coder : l.coder).key("coder_name").value(coder_name(i));
      j.end_object();
    }
    j.end_array().end_object();
    std::fputs(j.str().c_str(), stdout);
    return kOk;
  }
  std::printf("%s: HMC %d.%d, %s, q = %d, origin (%s, %s, %s), step %s, %llu bytes\n", in.c_str(), s.version_major,
              s.version_minor, kind_name(s.kind), s.quantizer.bits, g17(s.quantizer.origin[0]).c_str(),
              g17(s.quantizer.origin[1]).c_str(), g17(s.quantizer.origin[2]).c_str(), g17(s.quantizer.step).c_str(),
              static_cast<unsigned long long>(s.total_bytes));
  std::printf("\nchunks:\n%6s %10s %10s  %s\n", "type", "offset", "length", "");
  for (const auto& c : s.chunks)
    std::printf("%6s %10llu %10u  %s%s\n", c.type.c_str(), static_cast<unsigned long long>(c.offset), c.length,
                c.critical ? "critical" : "ancillary", c.known ? "" : ", unknown (skipped)");
  std::printf("\nlevels (coarsest first):\n%6s %10s %10s %12s %12s %12s  %s\n", "level", "points", "new", "layer bytes",
              "prefix bytes", "bits/point", "coder");
  for (std::size_t i = 0; i < s.levels.size(); ++i) {
    const auto& l = s.levels[i];
    std::printf("%6d %10llu %10llu %12llu %12llu %12.3f  %s\n", l.lod, static_cast<unsigned long long>(l.points),
                static_cast<unsigned long long>(l.new_points), static_cast<unsigned long long>(l.layer_bytes),
                static_cast<unsigned long long>(l.stream_bytes),
                8.0 * static_cast<double>(l.stream_bytes) / static_cast<double>(l.points),
                coder_name(i));
  }
  if (s.truncated) std::printf("\nwarning: %s\n", s.warning.c_str());
  return kOk;
}

}  // namespace hmc::cli
