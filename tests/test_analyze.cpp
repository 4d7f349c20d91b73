// SPDX-License-Identifier: AGPL-3.0-or-later
// `hmc analyze`, run as a user runs it: the thesis' per-level tables in
// --json form. Layers L0 ... Ln and global alpha on every volume level (the
// coarsest too), null (not 0) where a value is not defined, no key twice in
// an object, the encoder's options, and the same rows for a mesh and for the
// stream made from it with the same options.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "hmc/meshio.hpp"
#include "samples.hpp"
#include "support/run_hmc.hpp"
#include "support/temp_dir.hpp"

namespace fs = std::filesystem;
using namespace hmc;
using hmc::testgen::hmc_run;
using hmc::testgen::q;
using hmc::testgen::Run;
using hmc::testgen::slurp;

namespace {

// ---- A small JSON reader that remembers repeated keys ------------------------

struct JValue {
  enum Type { null, boolean, number, string, array, object } type = null;
  bool b = false;
  double num = 0;
  std::string str;
  std::vector<JValue> items;
  std::vector<std::pair<std::string, JValue>> members;

  bool has(const std::string& k) const {
    for (const auto& m : members)
      if (m.first == k) return true;
    return false;
  }
  const JValue& operator[](const std::string& k) const {
    for (const auto& m : members)
      if (m.first == k) return m.second;
    throw std::runtime_error("no key " + k);
  }
  const JValue& operator[](std::size_t i) const { return items.at(i); }
  std::size_t size() const { return type == array ? items.size() : members.size(); }
  bool is_null() const { return type == null; }
  bool is_number() const { return type == number; }
  std::string text() const { return type == string ? str : std::string(); }
};

class JsonReader {
 public:
  explicit JsonReader(const std::string& s) : s_(s) {}
  JValue parse() {
    JValue v = value();
    ws();
    if (i_ != s_.size()) fail("trailing characters");
    return v;
  }
  // "path: key" for every key that occurs twice in one object.
  std::vector<std::string> duplicates;

 private:
  void fail(const std::string& why) { throw std::runtime_error("JSON: " + why + " at " + std::to_string(i_)); }
  void ws() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool eat(const char* word) {
    const std::size_t n = std::char_traits<char>::length(word);
    if (s_.compare(i_, n, word) != 0) return false;
    i_ += n;
    return true;
  }
  std::string string_literal() {
    if (s_[i_] != '"') fail("string expected");
    ++i_;
    std::string out;
    while (i_ < s_.size() && s_[i_] != '"') {
      if (s_[i_] == '\\') {
        ++i_;
        if (i_ >= s_.size()) fail("bad escape");
        const char c = s_[i_];
        if (c == 'u') {
          out += '?';
          i_ += 4;
        } else {
          out += c == 'n' ? '\n' : c == 't' ? '\t' : c;
        }
        ++i_;
      } else {
        out += s_[i_++];
      }
    }
    if (i_ >= s_.size()) fail("unterminated string");
    ++i_;
    return out;
  }
  JValue value() {
    ws();
    if (i_ >= s_.size()) fail("value expected");
    JValue v;
    const char c = s_[i_];
    if (c == '{') {
      v.type = JValue::object;
      ++i_;
      ws();
      std::set<std::string> seen;
      if (s_[i_] == '}') {
        ++i_;
        return v;
      }
      while (true) {
        ws();
        std::string k = string_literal();
        if (!seen.insert(k).second) duplicates.push_back(k);
        ws();
        if (s_[i_] != ':') fail("':' expected");
        ++i_;
        JValue m = value();
        v.members.emplace_back(std::move(k), std::move(m));
        ws();
        if (s_[i_] == ',') {
          ++i_;
          continue;
        }
        if (s_[i_] == '}') {
          ++i_;
          return v;
        }
        fail("',' or '}' expected");
      }
    }
    if (c == '[') {
      v.type = JValue::array;
      ++i_;
      ws();
      if (s_[i_] == ']') {
        ++i_;
        return v;
      }
      while (true) {
        v.items.push_back(value());
        ws();
        if (s_[i_] == ',') {
          ++i_;
          continue;
        }
        if (s_[i_] == ']') {
          ++i_;
          return v;
        }
        fail("',' or ']' expected");
      }
    }
    if (c == '"') {
      v.type = JValue::string;
      v.str = string_literal();
      return v;
    }
    if (eat("null")) return v;
    if (eat("true") || eat("false")) {
      v.type = JValue::boolean;
      v.b = s_[i_ - 1] == 'e' && s_[i_ - 2] == 'u';
      return v;
    }
    const char* start = s_.c_str() + i_;
    char* end = nullptr;
    v.num = std::strtod(start, &end);
    if (end == start) fail("number expected");
    v.type = JValue::number;
    i_ += static_cast<std::size_t>(end - start);
    return v;
  }
  const std::string& s_;
  std::size_t i_ = 0;
};

// ---- Running hmc ---------------------------------------------------------------


// Runs `hmc ARGS` (which must succeed and print JSON) and parses its output;
// fails the test if any object repeats a key.
JValue hmc_json(const std::string& dir, const std::string& args) {
  const Run r = hmc_run(dir, args);
  INFO("hmc " << args);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  JsonReader reader(r.out);
  JValue v;
  REQUIRE_NOTHROW(v = reader.parse());
  std::string dups;
  for (const auto& k : reader.duplicates) dups += " " + k;
  CHECK_MESSAGE(reader.duplicates.empty(), "repeated keys:" << dups);
  return v;
}

std::vector<std::uint64_t> integers(const JValue& a) {
  std::vector<std::uint64_t> out;
  for (const auto& x : a.items) out.push_back(static_cast<std::uint64_t>(x.num));
  return out;
}

// A 500-point ball, analysed as a volume (the decoder's tetrahedra are its mesh).
std::string write_ball(const std::string& dir) {
  const std::string path = dir + "/ball.xyz";
  REQUIRE(io::write_mesh(path, samples::random_ball(500, 11)).ok());
  return path;
}

}  // namespace

TEST_CASE("analyze, volume: layers, classification and global alpha on every level, the coarsest too") {
  const auto dir = testgen::temp_dir("analyze_volume");
  const std::string ball = write_ball(dir);
  const JValue a = hmc_json(dir, "analyze " + q(ball) + " --kind volume --levels 3 --json");
  CHECK(a["kind"].text() == "volume");
  CHECK(a["source"].text() == "mesh");
  REQUIRE(a["options"].type == JValue::object);
  CHECK(a["options"]["levels"].num == 3);
  CHECK(a["options"]["boundary"].text() == "linear");
  CHECK(a["options"]["fidelity"].text() == "shape");
  REQUIRE(a["options"]["optimizers"].size() == 3);
  const JValue& rows = a["levels"];
  REQUIRE(rows.size() == 9);  // 3 optimisers x 3 levels
  std::map<std::string, std::map<int, const JValue*>> by;
  for (const auto& row : rows.items) {
    const std::string opt = row["optimizer"].text();
    const int level = static_cast<int>(row["level"].num);
    CAPTURE(opt);
    CAPTURE(level);
    by[opt][level] = &row;
    // Layers on every level: they partition the level's vertices, L0 being
    // the boundary (faces owned by one tetrahedron).
    const auto layers = integers(row["layers"]);
    REQUIRE(!layers.empty());
    std::uint64_t sum = 0;
    for (auto n : layers) sum += n;
    CHECK(sum == static_cast<std::uint64_t>(row["vn"].num));
    const JValue& c = row["classification"];
    CHECK(layers[0] == static_cast<std::uint64_t>(c["boundary_by_faces"].num));
    CHECK(c["boundary_by_faces"].num == c["boundary_by_solid_angle"].num);
    CHECK(c["disagreements"].num == 0);  // the two methods agree on a valid tetrahedral mesh
    // Global alpha: the mean length of the tetrahedra's edges, a positive number.
    REQUIRE(row["ga"].is_number());
    CHECK(row["ga"].num > 0);
    CHECK(row["edges"].num > row["vn"].num);
    // Tetrahedron tests are numbers; triangle tests do not apply: null, not 0.
    for (const char* k : {"qt1", "qt2", "qt3", "qt4"}) CHECK(row[k].is_number());
    CHECK(row["tri_angle"].is_null());
    CHECK(row["tri_edge"].is_null());
    CHECK(row["details"]["tri_angle"]["count"].num == 0);
    CHECK(row["details"]["tri_angle"]["mean"].is_null());
    CHECK(row["details"]["tri_angle"]["min"].is_null());
    CHECK(row["details"]["qt1"]["count"].num == row["cn"].num);
    // The coarsest level was not decimated: nothing removed, no optimiser.
    if (level == 2) {
      CHECK(row["removed"].is_null());
      CHECK(row["optimizer_used"].is_null());
    } else {
      CHECK(row["removed"].num > 0);
      CHECK(row["optimizer_used"].text() == opt);
    }
  }
  REQUIRE(by.size() == 3);
  for (const char* o : {"forward", "backward", "greedy"}) REQUIRE(by[o].size() == 3);
  // Level 0 is the input for every optimiser.
  CHECK(integers((*by["forward"][0])["layers"]) == integers((*by["greedy"][0])["layers"]));
  CHECK((*by["forward"][0])["ga"].num == (*by["backward"][0])["ga"].num);

  // The layers of the decimated levels are the encoder's own (hmc enc --json).
  const JValue e = hmc_json(dir, "enc " + q(ball) + " --kind volume --levels 3 --optimizer backward -o " +
                                     q(dir + "/b.hmc") + " --json");
  for (const auto& lev : e["levels"].items) {
    const int level = static_cast<int>(lev["level"].num);
    CAPTURE(level);
    if (level == 2) continue;  // coarsest: the encoder does not layer it
    CHECK(integers(lev["layers"]) == integers((*by["backward"][level])["layers"]));
    CHECK(lev["classification_disagreements"].num == (*by["backward"][level])["classification"]["disagreements"].num);
  }
}

TEST_CASE("analyze, surface: null for the tetrahedron tests, no key twice") {
  const auto dir = testgen::temp_dir("analyze_surface");
  REQUIRE(io::write_mesh(dir + "/torus.ply", samples::torus(40, 20)).ok());
  const JValue a = hmc_json(dir, "analyze " + q(dir + "/torus.ply") + " --levels 3 --json");
  CHECK(a["kind"].text() == "surface");
  REQUIRE(a["levels"].size() == 3);
  for (const auto& row : a["levels"].items) {
    CAPTURE(row["level"].num);
    CHECK(row["nv"].num > 0);
    CHECK(row["triangles"].num > 0);
    CHECK(row["ga"].num > 0);
    for (const char* k : {"tri_angle", "tri_edge", "min_edge_ratio", "neighbour_max_edge_ratio",
                          "neighbour_min_max_edge_ratio"}) {
      REQUIRE(row[k].is_number());
      CHECK(row[k].num > 0);
      CHECK(row[k].num <= 1);
    }
    for (const char* k : {"qt1", "qt2", "qt3", "qt4"}) CHECK(row[k].is_null());
    CHECK(row["details"]["qt1"]["min"].is_null());
    CHECK(row["details"]["tri_edge"]["count"].num == row["triangles"].num);
    CHECK(row["optimizer_used"].is_null());  // no interior vertices to choose among
    CHECK(row["mec"].size() > 0);
  }
  CHECK(a["levels"][2]["removed"].is_null());
  CHECK(a["levels"][0]["removed"].num > 0);
}

TEST_CASE("analyze takes the encoder's options, and a stream gives the same rows as its mesh") {
  const auto dir = testgen::temp_dir("analyze_options");
  const std::string ball = write_ball(dir);
  // One optimiser, and options that change the hierarchy: echoed, and used.
  const JValue g = hmc_json(dir, "analyze " + q(ball) +
                                     " --kind volume --levels 3 --optimizer greedy --boundary constant --fidelity rule"
                                     " --ratio 0.5 --bits 11 --json");
  CHECK(g["q"].num == 11);
  CHECK(g["options"]["boundary"].text() == "constant");
  CHECK(g["options"]["fidelity"].text() == "rule");
  CHECK(g["options"]["ratio"].num == 0.5);
  REQUIRE(g["levels"].size() == 3);
  for (const auto& row : g["levels"].items) CHECK(row["optimizer"].text() == "greedy");
  const JValue g3 = hmc_json(dir, "analyze " + q(ball) + " --kind volume --levels 3 --optimizer greedy --json");
  CHECK(g3["levels"][1]["vn"].num != g["levels"][1]["vn"].num);  // ratio 0.5 removes more than 0.3
  const JValue two = hmc_json(dir, "analyze " + q(ball) + " --kind volume --levels 2 --optimizer forward,best --json");
  REQUIRE(two["levels"].size() == 4);
  CHECK(two["levels"][2]["optimizer"].text() == "best");

  // The stream made with the same options: the same rows, the optimiser unknown (null).
  REQUIRE(hmc_run(dir, "enc " + q(ball) + " --kind volume --levels 3 --fidelity rule --boundary constant -o " +
                           q(dir + "/b.hmc")).code == 0);
  const JValue m = hmc_json(dir, "analyze " + q(ball) +
                                     " --kind volume --levels 3 --optimizer best --fidelity rule --boundary constant --json");
  const JValue s = hmc_json(dir, "analyze " + q(dir + "/b.hmc") + " --json");
  CHECK(s["source"].text() == "stream");
  CHECK(s["options"].is_null());
  REQUIRE(s["levels"].size() == m["levels"].size());
  for (std::size_t i = 0; i < s["levels"].size(); ++i) {
    const JValue &x = s["levels"][i], &y = m["levels"][i];
    CAPTURE(i);
    CHECK(x["optimizer"].is_null());
    CHECK(x["removed"].is_null());
    CHECK(x["level"].num == y["level"].num);
    CHECK(x["vn"].num == y["vn"].num);
    CHECK(x["cn"].num == y["cn"].num);
    CHECK(integers(x["layers"]) == integers(y["layers"]));
    CHECK(x["ga"].num == y["ga"].num);
    CHECK(x["qt1"].num == y["qt1"].num);
  }

  // Usage errors: exit 1 with a message.
  for (const std::string bad : {"--optimizer sideways", "--optimizer forward,", "--boundary wavy", "--fidelity perfect",
                                "--kind blob", "--ratio 0", "--ratio 1.5", "--levels 0", "--bits 22", "--fidelity"}) {
    CAPTURE(bad);
    const Run r = hmc_run(dir, "analyze " + q(ball) + " " + bad + " --json");
    CHECK(r.code == 1);
    CHECK(r.out.empty());
    CHECK(r.err.find("hmc analyze:") != std::string::npos);
  }
  // Encoder options do not apply to a stream.
  const Run r = hmc_run(dir, "analyze " + q(dir + "/b.hmc") + " --levels 3");
  CHECK(r.code == 1);
  CHECK(r.err.find("does not apply to a stream") != std::string::npos);
}
