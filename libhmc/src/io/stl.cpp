// SPDX-License-Identifier: AGPL-3.0-or-later
// STL, ascii and binary. STL stores every triangle with its own copies of
// the corners; identical coordinates are merged into one indexed vertex.
#include <cmath>
#include <cstring>
#include <unordered_map>
#include <vector>

#include "io/common.hpp"
#include "io/input.hpp"

namespace hmc::io::detail {

namespace {

struct Key {
  std::uint64_t bits[3];
  bool operator==(const Key& o) const noexcept {
    return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
  }
};

struct KeyHash {
  std::size_t operator()(const Key& k) const noexcept {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (std::uint64_t b : k.bits) {
      h ^= b + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
      h *= 0xff51afd7ed558ccdull;
    }
    return static_cast<std::size_t>(h ^ (h >> 32));
  }
};

class Merger {
 public:
  explicit Merger(Mesh& m) : m_(m) {}
  void reserve(std::size_t corners) { map_.reserve(corners / 4); }

  std::uint32_t add(const Vec3& p) {
    Key k;
    for (int i = 0; i < 3; ++i) {
      const double c = p[i] == 0.0 ? 0.0 : p[i];  // -0 and +0 are the same point
      std::memcpy(&k.bits[i], &c, sizeof c);
    }
    const auto next = static_cast<std::uint32_t>(m_.points.size());
    const auto [it, inserted] = map_.try_emplace(k, next);
    if (inserted) m_.points.push_back(p);
    return it->second;
  }

 private:
  Mesh& m_;
  std::unordered_map<Key, std::uint32_t, KeyHash> map_;
};

Mesh read_binary(Input& in, std::uint32_t count) {
  in.set_binary(true);
  in.skip(84, "binary STL header");
  Mesh m;
  Merger merge(m);
  m.triangles.reserve(count);
  merge.reserve(std::size_t{count} * 3);
  static const char* const axis[] = {"x", "y", "z"};
  for (std::uint32_t t = 0; t < count; ++t) {
    in.skip(12, "facet normal");
    Triangle tri;
    for (int c = 0; c < 3; ++c) {
      Vec3 p;
      for (int k = 0; k < 3; ++k) {
        p[k] = in.read_scalar(Scalar::f32, false, "facet vertex");
        if (!std::isfinite(p[k]))
          in.fail(std::string("non-finite ") + axis[k] + " coordinate in facet " + std::to_string(t));
      }
      tri[c] = merge.add(p);
    }
    in.skip(2, "facet attribute");
    m.triangles.push_back(tri);
  }
  return m;
}

Mesh read_ascii(Input& in) {
  Mesh m;
  Merger merge(m);
  std::vector<std::uint32_t> corners;
  std::string_view tok = in.token("solid");
  if (!iequals(tok, "solid")) in.fail("expected solid, found " + quote(tok));
  in.skip_line();  // the solid's name
  bool in_solid = true;
  while (in.next_token(tok)) {
    if (!in_solid) {
      if (!iequals(tok, "solid")) in.fail("expected solid, found " + quote(tok));
      in.skip_line();
      in_solid = true;
      continue;
    }
    if (iequals(tok, "endsolid")) {
      in.skip_line();
      in_solid = false;
      continue;
    }
    if (!iequals(tok, "facet")) in.fail("expected facet or endsolid, found " + quote(tok));
    in.expect_keyword("normal");
    // Normals are recomputed by every consumer and are often NaN in files
    // written for degenerate facets, so they are not checked.
    for (int k = 0; k < 3; ++k) in.token("normal component");
    in.expect_keyword("outer");
    in.expect_keyword("loop");
    corners.clear();
    for (;;) {
      tok = in.token("vertex or endloop");
      if (iequals(tok, "endloop")) break;
      if (!iequals(tok, "vertex")) in.fail("expected vertex or endloop, found " + quote(tok));
      Vec3 p;
      p[0] = in.real(in.token("x coordinate"), "x coordinate");
      p[1] = in.real(in.token("y coordinate"), "y coordinate");
      p[2] = in.real(in.token("z coordinate"), "z coordinate");
      if (m.points.size() >= 0xffffffffull) in.fail("too many vertices for 32-bit indices");
      corners.push_back(merge.add(p));
    }
    if (corners.size() < 3) in.fail("facet has " + std::to_string(corners.size()) + " vertices (at least 3 needed)");
    add_fan(m, corners.data(), corners.size());
    in.expect_keyword("endfacet");
  }
  if (in_solid) in.fail("unexpected end of file, expected endsolid");
  return m;
}

bool starts_with_solid(std::string_view data) {
  std::size_t i = 0;
  while (i < data.size() && is_space(data[i])) ++i;
  return istarts_with(data.substr(i), "solid");
}

}  // namespace

Mesh read_stl(const std::string& name, std::string_view data) {
  Input in(name, data);
  if (data.size() >= 84) {
    const auto count = load_uint<std::uint32_t>(reinterpret_cast<const unsigned char*>(data.data()) + 80, false);
    const std::uint64_t expected = 84 + 50 * std::uint64_t{count};
    if (expected == data.size()) return read_binary(in, count);
    if (!starts_with_solid(data))
      in.fail_at_offset(80, "binary STL declares " + std::to_string(count) + " triangles (" +
                                std::to_string(expected) + " bytes) but the file has " + std::to_string(data.size()) +
                                " bytes");
  }
  if (!starts_with_solid(data)) in.fail("not an STL file (no 'solid' and too short for binary STL)");
  return read_ascii(in);
}

}  // namespace hmc::io::detail
