// SPDX-License-Identifier: AGPL-3.0-or-later
// Out-of-tree consumer (C++, find_package): streams a file through the C API
// wrapper <hmc/hmc.hpp>, checks it against whole-buffer decoding and the C++
// API <hmc/codec.hpp>, and encodes the finest level's points again.
#include <hmc/codec.hpp>
#include <hmc/hmc.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer_cxx STREAM.hmc\n");
    return 1;
  }
  std::ifstream in(argv[1], std::ios::binary);
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto created = hmc::capi::Decoder::create();
  if (!created) return 2;
  hmc::capi::Decoder& dec = created.value();
  std::size_t seen = 0;
  for (std::size_t pos = 0; pos < bytes.size(); pos += 997) {
    auto n = dec.feed(bytes.data() + pos, std::min<std::size_t>(997, bytes.size() - pos));
    if (!n) {
      std::fprintf(stderr, "consumer_cxx: %s\n", n.error().to_string().c_str());
      return 3;
    }
    for (; seen < n.value(); ++seen) {
      const hmc_level_info li = dec.level_info(seen).value();
      std::printf("level %d: %llu vertices, %llu triangles\n", li.lod, (unsigned long long)li.point_count,
                  (unsigned long long)li.triangle_count);
    }
  }
  auto end = dec.finish();
  if (!end || end.value() != HMC_OK) {
    std::fprintf(stderr, "consumer_cxx: the stream did not end cleanly: %s\n", dec.message().c_str());
    return 3;
  }
  // The C++ API agrees.
  auto whole = hmc::decode(bytes.data(), bytes.size());
  if (!whole || whole.value().levels.size() != seen) {
    std::fprintf(stderr, "consumer_cxx: hmc::decode disagrees\n");
    return 4;
  }
  // Encode the finest level's positions again (RAII buffers throughout).
  auto xyz = dec.positions(seen - 1);
  auto tris = dec.triangles(seen - 1);
  auto enc = hmc::capi::Encoder::create();
  if (!xyz || !tris || !enc) return 5;
  auto again = enc.value().encode(xyz.value().data(), xyz.value().size() / 3, tris.value().data(),
                                  tris.value().size() / 3);
  if (!again) {
    std::fprintf(stderr, "consumer_cxx: %s\n", again.error().to_string().c_str());
    return 5;
  }
  // One level of a solid surface: nothing to note.
  if (!enc.value().notes().empty()) {
    std::fprintf(stderr, "consumer_cxx: unexpected encoder notes: %s\n", enc.value().notes().c_str());
    return 8;
  }
  auto check = hmc::capi::Decoder::create();
  if (!check || !check.value().decode(again.value().data(), again.value().size())) return 6;
  const auto finest = check.value().level_info(0).value();
  std::printf("consumer_cxx: %zu levels, libhmc %s; re-encoded %llu vertices into %zu bytes\n", seen,
              hmc_version_string(), (unsigned long long)finest.point_count, again.value().size());
  return finest.point_count == xyz.value().size() / 3 ? 0 : 7;
}
