// SPDX-License-Identifier: AGPL-3.0-or-later
#include "pointset/octree.hpp"

#include <algorithm>
#include <string>

#include "entropy/huffman.hpp"
#include "util/error.hpp"
#include "util/radix_sort.hpp"

namespace hmc::detail {

std::uint64_t morton_key(const GridPoint& p, int q) {
  std::uint64_t key = 0;
  for (int b = q - 1; b >= 0; --b)
    key = (key << 3) | (((p[0] >> b) & 1u) << 2) | (((p[1] >> b) & 1u) << 1) | ((p[2] >> b) & 1u);
  return key;
}

GridPoint morton_point(std::uint64_t key, int q) {
  GridPoint p{0, 0, 0};
  for (int b = 0; b < q; ++b) {
    const auto c = static_cast<std::uint32_t>(key >> (3 * b));
    p[0] |= ((c >> 2) & 1u) << b;
    p[1] |= ((c >> 1) & 1u) << b;
    p[2] |= (c & 1u) << b;
  }
  return p;
}

void sort_canonical(std::vector<GridPoint>& points) {
  // Coordinates are below 2^21, so (x, y, z) packs into one key that sorts
  // in canonical order.
  std::vector<std::uint64_t> keys(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    keys[i] = (std::uint64_t{points[i][0]} << 42) | (std::uint64_t{points[i][1]} << 21) | points[i][2];
  radix_sort(keys, 63);
  for (std::size_t i = 0; i < points.size(); ++i)
    points[i] = {static_cast<std::uint32_t>(keys[i] >> 42), static_cast<std::uint32_t>((keys[i] >> 21) & 0x1fffff),
                 static_cast<std::uint32_t>(keys[i] & 0x1fffff)};
}

std::vector<std::uint8_t> encode_octree(const std::vector<GridPoint>& points, int q) {
  std::vector<std::uint64_t> keys(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) keys[i] = morton_key(points[i], q);
  radix_sort(keys, 3 * q);

  // Occupancy symbols per depth, in breadth-first (= Morton) order.
  std::vector<std::vector<std::uint8_t>> symbols(static_cast<std::size_t>(q));
  for (int d = 0; d < q; ++d) {
    const int shift = 3 * (q - d);  // node key at depth d = key >> shift
    auto& out = symbols[static_cast<std::size_t>(d)];
    std::size_t i = 0;
    while (i < keys.size()) {
      const std::uint64_t node = keys[i] >> shift;
      std::uint8_t occ = 0;
      for (; i < keys.size() && (keys[i] >> shift) == node; ++i)
        occ = static_cast<std::uint8_t>(occ | (1u << ((keys[i] >> (shift - 3)) & 7u)));
      out.push_back(occ);
    }
  }

  BitWriter w;
  std::vector<HuffmanCode> codes;
  for (const auto& syms : symbols) {
    std::vector<std::uint64_t> freq(256, 0);
    for (std::uint8_t s : syms) ++freq[s];
    codes.push_back(HuffmanCode::from_frequencies(freq));
    codes.back().write(w);
  }
  for (int d = 0; d < q; ++d)
    for (std::uint8_t s : symbols[static_cast<std::size_t>(d)]) codes[static_cast<std::size_t>(d)].encode(w, s);
  return w.finish();
}

std::vector<GridPoint> decode_octree(const std::uint8_t* data, std::size_t size, int q, std::uint64_t n) {
  BitReader in(data, size, "BASE octree");
  std::vector<HuffmanCode> codes;
  for (int d = 0; d < q; ++d) codes.push_back(HuffmanCode::read(in, 256, "BASE octree table for depth " + std::to_string(d)));

  std::vector<std::uint64_t> nodes{0}, next;
  for (int d = 0; d < q; ++d) {
    next.clear();
    for (std::uint64_t node : nodes) {
      const std::uint32_t occ = codes[static_cast<std::size_t>(d)].decode(in);
      if (occ == 0) fail(Status::bad_layer, "BASE octree: empty occupancy at depth " + std::to_string(d));
      for (std::uint32_t c = 0; c < 8; ++c)
        if (occ & (1u << c)) {
          if (next.size() == n)
            fail(Status::bad_layer, "BASE octree: more than the declared " + std::to_string(n) + " points");
          next.push_back((node << 3) | c);
        }
    }
    nodes.swap(next);
  }
  in.expect_end();
  if (nodes.size() != n)
    fail(Status::bad_layer, "BASE octree: " + std::to_string(nodes.size()) + " points, the header declares " +
                                std::to_string(n));
  std::vector<GridPoint> points(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) points[i] = morton_point(nodes[i], q);
  sort_canonical(points);
  return points;
}

}  // namespace hmc::detail
