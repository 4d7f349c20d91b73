// SPDX-License-Identifier: AGPL-3.0-or-later
// Gmsh MSH 2.2 and 4.1, ascii and binary.
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

#include "io/common.hpp"
#include "io/input.hpp"

namespace hmc::io::detail {

namespace {

constexpr std::uint64_t kMaxPoints = std::numeric_limits<std::uint32_t>::max();
constexpr int kTriangle = 2;
constexpr int kTetrahedron = 4;

// Nodes of each fixed-size element type (Gmsh's numbering); binary sections
// give no element sizes, so an element of a type not listed cannot be skipped.
int nodes_per_element(std::int64_t type) noexcept {
  static const int table[] = {
      -1, 2,  3,  4,  4,  8,  6,  5,  3,  6,   // 0-9
      9,  10, 27, 18, 14, 1,  8,  20, 15, 13,  // 10-19
      9,  10, 12, 15, 15, 21, 4,  5,  6,  20,  // 20-29
      35, 56,                                  // 30-31
  };
  if (type >= 0 && type < static_cast<std::int64_t>(sizeof table / sizeof table[0]))
    return table[static_cast<std::size_t>(type)];
  if (type == 92) return 64;
  if (type == 93) return 125;
  return -1;
}

// Gmsh node tags are arbitrary positive integers; this maps them to indices,
// through a table when they are dense and a hash map otherwise.
class NodeMap {
 public:
  void reserve(std::size_t n) { tags_.reserve(n); }
  void add(std::uint64_t tag) { tags_.push_back(tag); }
  std::size_t size() const noexcept { return tags_.size(); }

  void build(Input& in) {
    if (tags_.empty()) return;
    min_ = max_ = tags_[0];
    for (std::uint64_t t : tags_) {
      if (t < min_) min_ = t;
      if (t > max_) max_ = t;
    }
    const std::uint64_t n = tags_.size();
    if (max_ - min_ < 4 * n + 1024) {
      dense_.assign(static_cast<std::size_t>(max_ - min_ + 1), kNone);
      for (std::size_t i = 0; i < tags_.size(); ++i) {
        std::uint32_t& slot = dense_[static_cast<std::size_t>(tags_[i] - min_)];
        if (slot != kNone) duplicate(in, tags_[i]);
        slot = static_cast<std::uint32_t>(i);
      }
    } else {
      sparse_.reserve(tags_.size());
      for (std::size_t i = 0; i < tags_.size(); ++i)
        if (!sparse_.emplace(tags_[i], static_cast<std::uint32_t>(i)).second) duplicate(in, tags_[i]);
    }
    std::vector<std::uint64_t>().swap(tags_);
  }

  bool find(std::uint64_t tag, std::uint32_t& index) const noexcept {
    if (!dense_.empty()) {
      if (tag < min_ || tag - min_ >= dense_.size()) return false;
      index = dense_[static_cast<std::size_t>(tag - min_)];
      return index != kNone;
    }
    const auto it = sparse_.find(tag);
    if (it == sparse_.end()) return false;
    index = it->second;
    return true;
  }

 private:
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  [[noreturn]] static void duplicate(Input& in, std::uint64_t tag) {
    in.fail("duplicate node tag " + std::to_string(tag) + " in $Nodes");
  }

  std::vector<std::uint64_t> tags_;
  std::uint64_t min_ = 0, max_ = 0;
  std::vector<std::uint32_t> dense_;
  std::unordered_map<std::uint64_t, std::uint32_t> sparse_;
};

class Reader {
 public:
  Reader(const std::string& name, std::string_view data) : in_(name, data) {}

  Mesh run() {
    read_format();
    std::string_view line;
    while (in_.next_line(line)) {
      line = trim(line);
      if (line.empty()) continue;
      if (line[0] != '$') in_.fail("expected a section such as $Nodes, found " + quote(line));
      const std::string_view section = line.substr(1);
      if (section == "Nodes") {
        if (have_nodes_) in_.fail("second $Nodes section");
        have_nodes_ = true;
        if (v4_) binary_ ? nodes4_binary() : nodes4_ascii();
        else binary_ ? nodes2_binary() : nodes2_ascii();
        expect_end("$EndNodes");
        nodes_.build(in_);
      } else if (section == "Elements") {
        if (!have_nodes_) in_.fail("$Elements before $Nodes");
        if (v4_) binary_ ? elements4_binary() : elements4_ascii();
        else binary_ ? elements2_binary() : elements2_ascii();
        expect_end("$EndElements");
      } else {
        skip_section(section);
      }
    }
    if (!have_nodes_) in_.fail("no $Nodes section");
    return std::move(mesh_);
  }

 private:
  void read_format() {
    std::string_view line;
    if (!in_.next_line(line)) in_.fail("empty file, expected $MeshFormat");
    line = trim(line);
    if (line == "$NOD")
      hmc::detail::fail(Status::unsupported_format, in_.name() + ": Gmsh MSH version 1 files are not supported");
    if (line != "$MeshFormat") in_.fail("expected $MeshFormat, found " + quote(line));
    Fields f;
    if (!in_.next_data_line(f)) in_.fail("unexpected end of file in $MeshFormat");
    std::string_view version, type, size;
    if (!f.next(version) || !f.next(type) || !f.next(size))
      in_.fail("$MeshFormat needs a version, a file type and a data size");
    if (version == "4.1") {
      v4_ = true;
    } else if (!(version == "2" || (version.size() > 2 && version.substr(0, 2) == "2."))) {
      hmc::detail::fail(Status::unsupported_format, in_.name() + ":" + std::to_string(in_.line()) +
                                                        ": Gmsh MSH version " + quote(version) +
                                                        " is not supported (only 2.x and 4.1)");
    }
    const std::int64_t t = in_.integer(type, "file type");
    if (t != 0 && t != 1) in_.fail("file type must be 0 (ascii) or 1 (binary), not " + std::to_string(t));
    binary_ = t == 1;
    if (in_.integer(size, "data size") != 8) in_.fail("data size must be 8, not " + std::string(size));
    if (binary_) {
      const unsigned char* p = in_.take(4, "endianness marker");
      if (load_uint<std::uint32_t>(p, false) == 1) big_ = false;
      else if (load_uint<std::uint32_t>(p, true) == 1) big_ = true;
      else in_.fail_at_offset(in_.mark(), "bad endianness marker in $MeshFormat (expected the integer 1)");
      in_.skip_line();
      in_.set_binary(true);
    }
    expect_end("$EndMeshFormat");
  }

  void expect_end(std::string_view end) {
    std::string_view line;
    while (in_.next_line(line)) {
      line = trim(line);
      if (line.empty()) continue;
      if (line != end) in_.fail("expected " + std::string(end) + ", found " + quote(line));
      return;
    }
    in_.fail("unexpected end of file, expected " + std::string(end));
  }

  void skip_section(std::string_view section) {
    const std::string end = "$End" + std::string(section);
    const std::string_view data = in_.data();
    std::size_t from = in_.pos();
    for (;;) {
      const std::size_t k = data.find(end, from);
      if (k == std::string_view::npos)
        in_.fail("section $" + std::string(section) + " has no " + end);
      const std::size_t after = k + end.size();
      if ((k == 0 || data[k - 1] == '\n') && (after == data.size() || is_space(data[after]))) {
        in_.skip_to(k);
        in_.skip_line();
        return;
      }
      from = k + 1;
    }
  }

  // ---- shared helpers ----

  std::uint64_t count_line(std::string_view what) {
    Fields f;
    if (!in_.next_data_line(f)) in_.fail("unexpected end of file, expected " + std::string(what));
    std::string_view tok;
    f.next(tok);
    return in_.count(tok, what);
  }

  void check_points(std::uint64_t n) {
    if (n > kMaxPoints - mesh_.points.size()) in_.fail("too many nodes (" + std::to_string(n) + ")");
  }

  void add_point(const Vec3& p) { mesh_.points.push_back(p); }

  double coordinate(const char* what) {
    const double v = in_.read_f64(big_, what);
    if (!std::isfinite(v)) in_.fail(std::string("non-finite ") + what);
    return v;
  }

  std::uint32_t node_index(std::uint64_t tag) {
    std::uint32_t i;
    if (!nodes_.find(tag, i)) in_.fail("element references unknown node tag " + std::to_string(tag));
    return i;
  }

  void add_element(std::int64_t type, const std::uint64_t* tags) {
    if (type == kTriangle) mesh_.triangles.push_back({node_index(tags[0]), node_index(tags[1]), node_index(tags[2])});
    else if (type == kTetrahedron)
      mesh_.tetrahedra.push_back({node_index(tags[0]), node_index(tags[1]), node_index(tags[2]), node_index(tags[3])});
  }

  static bool kept(std::int64_t type) noexcept { return type == kTriangle || type == kTetrahedron; }

  std::string_view field(Fields& f, std::string_view what) {
    std::string_view tok;
    if (!f.next(tok)) in_.fail("missing " + std::string(what));
    return tok;
  }

  // Reads the element's nodes from an ascii line if its type is kept.
  void ascii_element(std::int64_t type, Fields& f) {
    if (!kept(type)) return;
    std::uint64_t tags[4];
    const int n = nodes_per_element(type);
    for (int k = 0; k < n; ++k) tags[k] = in_.count(field(f, "element node"), "element node tag");
    add_element(type, tags);
  }

  Vec3 ascii_coordinates(Fields& f) {
    Vec3 p;
    p[0] = in_.real(field(f, "x coordinate"), "x coordinate");
    p[1] = in_.real(field(f, "y coordinate"), "y coordinate");
    p[2] = in_.real(field(f, "z coordinate"), "z coordinate");
    return p;
  }

  // ---- MSH 2.2 ----

  void nodes2_ascii() {
    const std::uint64_t n = count_line("node count");
    check_points(n);
    in_.check_text_count(n, 4, "node");
    mesh_.points.reserve(static_cast<std::size_t>(n));
    nodes_.reserve(static_cast<std::size_t>(n));
    Fields f;
    for (std::uint64_t i = 0; i < n; ++i) {
      if (!in_.next_data_line(f)) in_.fail("unexpected end of file in $Nodes");
      nodes_.add(in_.count(field(f, "node tag"), "node tag"));
      add_point(ascii_coordinates(f));
    }
  }

  void nodes2_binary() {
    const std::uint64_t n = count_line("node count");
    check_points(n);
    in_.check_binary_count(n, 28, "node");
    mesh_.points.reserve(static_cast<std::size_t>(n));
    nodes_.reserve(static_cast<std::size_t>(n));
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::int32_t tag = in_.read_i32(big_, "node tag");
      if (tag < 0) in_.fail("negative node tag " + std::to_string(tag));
      nodes_.add(static_cast<std::uint64_t>(tag));
      Vec3 p;
      p[0] = coordinate("x coordinate");
      p[1] = coordinate("y coordinate");
      p[2] = coordinate("z coordinate");
      add_point(p);
    }
  }

  void elements2_ascii() {
    const std::uint64_t n = count_line("element count");
    in_.check_text_count(n, 3, "element");
    Fields f;
    for (std::uint64_t i = 0; i < n; ++i) {
      if (!in_.next_data_line(f)) in_.fail("unexpected end of file in $Elements");
      in_.integer(field(f, "element tag"), "element tag");
      const std::int64_t type = in_.integer(field(f, "element type"), "element type");
      const std::uint64_t ntags = in_.count(field(f, "number of tags"), "number of tags");
      for (std::uint64_t k = 0; k < ntags; ++k) field(f, "element tag");
      ascii_element(type, f);
    }
  }

  void elements2_binary() {
    const std::uint64_t n = count_line("element count");
    in_.check_binary_count(n, 8, "element");
    std::uint64_t done = 0;
    while (done < n) {
      const std::int32_t type = in_.read_i32(big_, "element type");
      const std::int32_t follow = in_.read_i32(big_, "element count of block");
      const std::int32_t ntags = in_.read_i32(big_, "number of tags");
      const int npe = nodes_per_element(type);
      if (npe < 0) in_.fail("unsupported element type " + std::to_string(type));
      if (follow <= 0 || static_cast<std::uint64_t>(follow) > n - done)
        in_.fail("bad element count " + std::to_string(follow) + " in element block");
      if (ntags < 0) in_.fail("negative number of tags " + std::to_string(ntags));
      const std::uint64_t record = 4 * (1 + static_cast<std::uint64_t>(ntags) + static_cast<std::uint64_t>(npe));
      in_.check_binary_count(static_cast<std::uint64_t>(follow), record, "element");
      for (std::int32_t j = 0; j < follow; ++j) {
        in_.skip(4 * (1 + static_cast<std::uint64_t>(ntags)), "element tags");
        if (!kept(type)) {
          in_.skip(4 * static_cast<std::uint64_t>(npe), "element nodes");
          continue;
        }
        std::uint64_t tags[4];
        for (int k = 0; k < npe; ++k) {
          const std::int32_t t = in_.read_i32(big_, "element node tag");
          tags[k] = t < 0 ? std::numeric_limits<std::uint64_t>::max() : static_cast<std::uint64_t>(t);
        }
        add_element(type, tags);
      }
      done += static_cast<std::uint64_t>(follow);
    }
  }

  // ---- MSH 4.1 ----

  void nodes4_ascii() {
    Fields f;
    if (!in_.next_data_line(f)) in_.fail("unexpected end of file in $Nodes");
    const std::uint64_t blocks = in_.count(field(f, "number of entity blocks"), "number of entity blocks");
    const std::uint64_t n = in_.count(field(f, "node count"), "node count");
    check_points(n);
    in_.check_text_count(blocks, 4, "entity block");
    in_.check_text_count(n, 4, "node");
    mesh_.points.reserve(static_cast<std::size_t>(n));
    nodes_.reserve(static_cast<std::size_t>(n));
    for (std::uint64_t b = 0; b < blocks; ++b) {
      if (!in_.next_data_line(f)) in_.fail("unexpected end of file in $Nodes");
      field(f, "entity dimension");
      field(f, "entity tag");
      field(f, "parametric flag");
      const std::uint64_t m = in_.count(field(f, "node count of block"), "node count of block");
      if (m > n - nodes_.size()) in_.fail("entity block has more nodes than $Nodes declares");
      for (std::uint64_t i = 0; i < m; ++i) {
        if (!in_.next_data_line(f)) in_.fail("unexpected end of file in $Nodes");
        nodes_.add(in_.count(field(f, "node tag"), "node tag"));
      }
      for (std::uint64_t i = 0; i < m; ++i) {
        if (!in_.next_data_line(f)) in_.fail("unexpected end of file in $Nodes");
        add_point(ascii_coordinates(f));
      }
    }
  }

  void nodes4_binary() {
    const std::uint64_t blocks = in_.read_uint<std::uint64_t>(big_, "number of entity blocks");
    const std::uint64_t n = in_.read_uint<std::uint64_t>(big_, "node count");
    in_.skip(16, "node tag range");
    check_points(n);
    in_.check_binary_count(n, 32, "node");
    in_.check_binary_count(blocks, 20, "entity block");
    mesh_.points.reserve(static_cast<std::size_t>(n));
    nodes_.reserve(static_cast<std::size_t>(n));
    for (std::uint64_t b = 0; b < blocks; ++b) {
      const std::int32_t dim = in_.read_i32(big_, "entity dimension");
      in_.read_i32(big_, "entity tag");
      const std::int32_t parametric = in_.read_i32(big_, "parametric flag");
      const std::uint64_t m = in_.read_uint<std::uint64_t>(big_, "node count of block");
      if (dim < 0 || dim > 3) in_.fail("bad entity dimension " + std::to_string(dim));
      if (m > n - nodes_.size()) in_.fail("entity block has more nodes than $Nodes declares");
      const std::uint64_t extra = parametric != 0 ? static_cast<std::uint64_t>(dim) : 0;
      in_.check_binary_count(m, 8 * (4 + extra), "node");
      for (std::uint64_t i = 0; i < m; ++i) nodes_.add(in_.read_uint<std::uint64_t>(big_, "node tag"));
      for (std::uint64_t i = 0; i < m; ++i) {
        Vec3 p;
        p[0] = coordinate("x coordinate");
        p[1] = coordinate("y coordinate");
        p[2] = coordinate("z coordinate");
        in_.skip(8 * extra, "parametric coordinates");
        add_point(p);
      }
    }
  }

  void elements4_ascii() {
    Fields f;
    if (!in_.next_data_line(f)) in_.fail("unexpected end of file in $Elements");
    const std::uint64_t blocks = in_.count(field(f, "number of entity blocks"), "number of entity blocks");
    in_.check_text_count(blocks, 4, "entity block");
    for (std::uint64_t b = 0; b < blocks; ++b) {
      if (!in_.next_data_line(f)) in_.fail("unexpected end of file in $Elements");
      field(f, "entity dimension");
      field(f, "entity tag");
      const std::int64_t type = in_.integer(field(f, "element type"), "element type");
      const std::uint64_t m = in_.count(field(f, "element count of block"), "element count of block");
      in_.check_text_count(m, 2, "element");
      for (std::uint64_t i = 0; i < m; ++i) {
        if (!in_.next_data_line(f)) in_.fail("unexpected end of file in $Elements");
        in_.count(field(f, "element tag"), "element tag");
        ascii_element(type, f);
      }
    }
  }

  void elements4_binary() {
    const std::uint64_t blocks = in_.read_uint<std::uint64_t>(big_, "number of entity blocks");
    in_.skip(24, "element count and tag range");
    in_.check_binary_count(blocks, 20, "entity block");
    for (std::uint64_t b = 0; b < blocks; ++b) {
      in_.read_i32(big_, "entity dimension");
      in_.read_i32(big_, "entity tag");
      const std::int32_t type = in_.read_i32(big_, "element type");
      const std::uint64_t m = in_.read_uint<std::uint64_t>(big_, "element count of block");
      const int npe = nodes_per_element(type);
      if (npe < 0) in_.fail("unsupported element type " + std::to_string(type));
      const std::uint64_t record = 8 * (1 + static_cast<std::uint64_t>(npe));
      in_.check_binary_count(m, record, "element");
      for (std::uint64_t i = 0; i < m; ++i) {
        in_.skip(8, "element tag");
        if (!kept(type)) {
          in_.skip(record - 8, "element nodes");
          continue;
        }
        std::uint64_t tags[4];
        for (int k = 0; k < npe; ++k) tags[k] = in_.read_uint<std::uint64_t>(big_, "element node tag");
        add_element(type, tags);
      }
    }
  }

  Input in_;
  Mesh mesh_;
  NodeMap nodes_;
  bool v4_ = false;
  bool binary_ = false;
  bool big_ = false;
  bool have_nodes_ = false;
};

}  // namespace

Mesh read_gmsh(const std::string& name, std::string_view data) { return Reader(name, data).run(); }

}  // namespace hmc::io::detail
