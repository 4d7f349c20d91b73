// SPDX-License-Identifier: AGPL-3.0-or-later
// The hmc command line, run as a user runs it: exit codes, messages,
// outputs, and nothing left behind on failure.
#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "hmc/codec.hpp"
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


std::size_t entries(const std::string& dir) {
  std::size_t n = 0;
  for (auto it = fs::directory_iterator(dir); it != fs::directory_iterator(); ++it) ++n;
  return n;
}

}  // namespace

TEST_CASE("enc, info and dec round trip through files, with matching canonical dumps") {
  const auto dir = testgen::temp_dir("cli_roundtrip");
  REQUIRE(io::write_mesh(dir + "/torus.ply", samples::torus(60, 30)).ok());
  auto r = hmc_run(dir, "enc " + q(dir + "/torus.ply") + " -o " + q(dir + "/t.hmc") + " --bits 11 --canonical " +
                            q(dir + "/enc-dump"));
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.out.find("1800 points") != std::string::npos);
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " -o " + q(dir + "/points.xyz") + " --canonical " + q(dir + "/dec-dump"));
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(slurp(dir + "/enc-dump/header.json") == slurp(dir + "/dec-dump/header.json"));
  CHECK(slurp(dir + "/enc-dump/level-0.points") == slurp(dir + "/dec-dump/level-0.points"));
  CHECK(slurp(dir + "/dec-dump/header.json").find("\"q\": 11") != std::string::npos);
  auto pts = io::read_mesh(dir + "/points.xyz");
  REQUIRE(pts.ok());
  CHECK(pts.value().points.size() == 1800);

  r = hmc_run(dir, "info " + q(dir + "/t.hmc") + " --json");
  REQUIRE(r.code == 0);
  CHECK(r.out.find("\"type\": \"HEAD\"") != std::string::npos);
  CHECK(r.out.find("\"points\": 1800") != std::string::npos);
  CHECK(r.out.find("\"kind\": \"surface\"") != std::string::npos);
  // The base layer's coder is named from its payload (the encoder writes
  // the octree or the ranked octree).
  const bool named =
      r.out.find("\"coder\": 0, \"coder_name\": \"octree\"") != std::string::npos ||
      r.out.find("\"coder\": 5, \"coder_name\": \"ranked octree\"") != std::string::npos;
  CHECK(named);

  // --fast-decode: the plain octree, the same points.
  r = hmc_run(dir, "enc " + q(dir + "/torus.ply") + " -o " + q(dir + "/f.hmc") + " --bits 11 --fast-decode");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  r = hmc_run(dir, "dec " + q(dir + "/f.hmc") + " --points-only --canonical " + q(dir + "/fast-dump"));
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(slurp(dir + "/enc-dump/level-0.points") == slurp(dir + "/fast-dump/level-0.points"));
  r = hmc_run(dir, "info " + q(dir + "/f.hmc") + " --json");
  CHECK(r.out.find("\"coder\": 0, \"coder_name\": \"octree\"") != std::string::npos);
}

TEST_CASE("enc notes a flat surface's missing connectivity and fewer levels than asked, in text and JSON") {
  const auto dir = testgen::temp_dir("cli_notes");
  REQUIRE(io::write_mesh(dir + "/flat.ply", samples::height_field(10, 0.0)).ok());
  auto r = hmc_run(dir, "enc " + q(dir + "/flat.ply") + " -o " + q(dir + "/f.hmc") + " --levels 2");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.out.find("note: the 100 points span no volume") != std::string::npos);
  CHECK(r.out.find("note: 1 of the 2 levels requested") != std::string::npos);
  r = hmc_run(dir, "enc " + q(dir + "/flat.ply") + " -o " + q(dir + "/f.hmc") + " --levels 2 --json");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.out.find("\"notes\": [\"the 100 points span no volume") != std::string::npos);
  // Nothing to note: an empty list, and no note line.
  REQUIRE(io::write_mesh(dir + "/torus.ply", samples::torus(30, 16)).ok());
  r = hmc_run(dir, "enc " + q(dir + "/torus.ply") + " -o " + q(dir + "/t.hmc") + " --json");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.out.find("\"notes\": []") != std::string::npos);
  r = hmc_run(dir, "enc " + q(dir + "/torus.ply") + " -o " + q(dir + "/t.hmc"));
  CHECK(r.out.find("note:") == std::string::npos);
}

TEST_CASE("enc without --levels writes a preview: a coarsest level of a few percent, the finest level the input") {
  const auto dir = testgen::temp_dir("cli_preview_default");
  REQUIRE(io::write_mesh(dir + "/torus.ply", samples::torus(80, 40)).ok());  // 3,200 points
  auto levels_of = [&](const std::string& name) {
    const std::string bytes = slurp(dir + "/" + name);
    auto info = inspect(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    REQUIRE(info.ok());
    std::vector<std::uint64_t> points;
    for (const auto& l : info.value().levels) points.push_back(l.points);
    return points;  // coarsest first
  };
  auto r = hmc_run(dir, "enc " + q(dir + "/torus.ply") + " -o " + q(dir + "/d.hmc"));
  REQUIRE_MESSAGE(r.code == 0, r.err);
  const auto d = levels_of("d.hmc");
  REQUIRE(d.size() >= 3);
  CHECK(d.back() == 3200);
  CHECK(static_cast<double>(d.front()) <= 0.04 * 3200);
  CHECK(static_cast<double>(d.front()) > 0.005 * 3200);  // still a preview, not a handful of points
  for (std::size_t i = 1; i < d.size(); ++i) CHECK(d[i] > d[i - 1]);
  // --levels alone: exactly those levels; --preview-ratio 0: none added.
  REQUIRE(hmc_run(dir, "enc " + q(dir + "/torus.ply") + " -o " + q(dir + "/l1.hmc") + " --levels 1").code == 0);
  CHECK(levels_of("l1.hmc") == std::vector<std::uint64_t>{3200});
  REQUIRE(hmc_run(dir, "enc " + q(dir + "/torus.ply") + " -o " + q(dir + "/p0.hmc") + " --preview-ratio 0").code == 0);
  CHECK(levels_of("p0.hmc") == std::vector<std::uint64_t>{3200});
  // An explicit ratio with --levels 2: one independent-set level, then cells.
  r = hmc_run(dir, "enc " + q(dir + "/torus.ply") + " -o " + q(dir + "/l2.hmc") + " --levels 2 --preview-ratio 0.1");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  const auto l2 = levels_of("l2.hmc");
  REQUIRE(l2.size() >= 3);
  CHECK(static_cast<double>(l2.front()) <= 0.1 * 3200);
  // Decoding the default stream gives the input's points at the finest level.
  r = hmc_run(dir, "dec " + q(dir + "/d.hmc") + " --canonical " + q(dir + "/dd"));
  REQUIRE_MESSAGE(r.code == 0, r.err);
  r = hmc_run(dir, "dec " + q(dir + "/l1.hmc") + " --canonical " + q(dir + "/d1"));
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(slurp(dir + "/dd/level-0.points") == slurp(dir + "/d1/level-0.points"));
  for (const char* bad : {"1", "-0.1", "x", "0.5x"}) {
    r = hmc_run(dir, "enc " + q(dir + "/torus.ply") + " -o " + q(dir + "/bad.hmc") + " --preview-ratio " + bad);
    CHECK(r.code == 1);
    CHECK(r.err.find("--preview-ratio must be a number in [0, 1)") != std::string::npos);
    CHECK_FALSE(fs::exists(dir + "/bad.hmc"));
  }
}

TEST_CASE("dec -o rebuilds only the level it writes; --all-levels rebuilds each, with the same finest mesh") {
  const auto dir = testgen::temp_dir("cli_rebuild");
  REQUIRE(io::write_mesh(dir + "/torus.ply", samples::torus(40, 16)).ok());
  auto r = hmc_run(dir, "enc " + q(dir + "/torus.ply") + " -o " + q(dir + "/t.hmc") + " --levels 3");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " -o " + q(dir + "/one.ply") + " --json");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  auto count = [](const std::string& s, const std::string& what) {
    std::size_t n = 0;
    for (auto at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
    return n;
  };
  CHECK(count(r.out, "\"rebuilt\": false") == 2);
  CHECK(count(r.out, "\"rebuilt\": true") == 1);
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " --all-levels " + q(dir + "/all") + " --json");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(count(r.out, "\"rebuilt\": true") == 3);
  CHECK(slurp(dir + "/one.ply") == slurp(dir + "/all/level-0.ply"));
  CHECK_FALSE(slurp(dir + "/one.ply").empty());
  // The text table marks levels without connectivity.
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " -o " + q(dir + "/two.ply"));
  REQUIRE(r.code == 0);
  CHECK(r.out.find(" - ") != std::string::npos);
  // Without outputs the summary shows every level; --rebuild overrides.
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " --json");
  REQUIRE(r.code == 0);
  CHECK(count(r.out, "\"rebuilt\": true") == 3);
  // Each level's phases are timed: its points always, its rebuild when
  // there is one.
  CHECK(count(r.out, "\"points_seconds\": ") == 3);
  CHECK(count(r.out, "\"rebuild_seconds\": ") == 3);
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " --json --rebuild finest");
  REQUIRE(r.code == 0);
  CHECK(count(r.out, "\"rebuilt\": false") == 2);
  CHECK(count(r.out, "\"points_seconds\": ") == 3);
  CHECK(count(r.out, "\"rebuild_seconds\": ") == 1);
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " --json --points-only");
  REQUIRE(r.code == 0);
  CHECK(count(r.out, "\"points_seconds\": ") == 3);
  CHECK(count(r.out, "\"rebuild_seconds\": ") == 0);
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " -o " + q(dir + "/three.ply") + " --json --rebuild all");
  REQUIRE(r.code == 0);
  CHECK(count(r.out, "\"rebuilt\": true") == 3);
  CHECK(slurp(dir + "/three.ply") == slurp(dir + "/one.ply"));
  // A level beyond the stream's coarsest decodes the coarsest, and says so.
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " --level 7 -o " + q(dir + "/far.ply"));
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.err.find("levels 0 to 2; decoded its coarsest, level 2") != std::string::npos);
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " --level 2 -o " + q(dir + "/coarsest.ply"));
  REQUIRE(r.code == 0);
  CHECK(r.err.find("warning") == std::string::npos);
  CHECK(slurp(dir + "/far.ply") == slurp(dir + "/coarsest.ply"));
  r = hmc_run(dir, "dec " + q(dir + "/t.hmc") + " --rebuild some");
  CHECK(r.code == 1);
  CHECK(r.err.find("--rebuild") != std::string::npos);
}

TEST_CASE("dec --all-levels writes a volume's tetrahedra as VTK unless --ext says otherwise") {
  const auto dir = testgen::temp_dir("cli_all_levels_volume");
  REQUIRE(io::write_mesh(dir + "/ball.xyz", samples::random_ball(400, 5)).ok());
  auto r = hmc_run(dir, "enc " + q(dir + "/ball.xyz") + " -o " + q(dir + "/v.hmc") + " --kind volume --levels 2");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  r = hmc_run(dir, "dec " + q(dir + "/v.hmc") + " --all-levels " + q(dir + "/all"));
  REQUIRE_MESSAGE(r.code == 0, r.err);
  for (const char* level : {"level-0.vtk", "level-1.vtk"}) {
    auto m = io::read_mesh(dir + "/all/" + level);
    REQUIRE_MESSAGE(m.ok(), level);
    CHECK_FALSE(m.value().tetrahedra.empty());
  }
  CHECK_FALSE(std::filesystem::exists(dir + "/all/level-0.ply"));
  // Points alone still go to PLY; an explicit PLY for tetrahedra is refused
  // as a usage error and leaves nothing behind.
  r = hmc_run(dir, "dec " + q(dir + "/v.hmc") + " --points-only --all-levels " + q(dir + "/pts"));
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(std::filesystem::exists(dir + "/pts/level-0.ply"));
  r = hmc_run(dir, "dec " + q(dir + "/v.hmc") + " --all-levels " + q(dir + "/bad") + " --ext ply");
  CHECK(r.code == 1);
  CHECK(r.err.find("tetrahedra") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir + "/bad"));
}

TEST_CASE("dec writes binary coordinates as float32 only when that keeps the grid") {
  const auto dir = testgen::temp_dir("cli_coords");
  auto coords_of = [&](const std::string& ply) {
    const std::string text = slurp(ply);
    return text.find("property float x") != std::string::npos    ? std::string("float")
           : text.find("property double x") != std::string::npos ? std::string("double")
                                                                  : std::string("?");
  };
  // Near the origin: float32 moves no coordinate by 1/16 of a step.
  REQUIRE(io::write_mesh(dir + "/near.xyz", samples::random_ball(300, 5)).ok());
  // Far from it (a georeferenced survey, say): float32 would move points by
  // many steps, so doubles are written.
  Mesh far = samples::random_ball(300, 5);
  for (Vec3& p : far.points) p[0] += 4.0e6;
  REQUIRE(io::write_mesh(dir + "/far.xyz", far).ok());
  for (const std::string name : {"near", "far"}) {
    auto r = hmc_run(dir, "enc " + q(dir + "/" + name + ".xyz") + " -o " + q(dir + "/" + name + ".hmc") + " --bits 12");
    REQUIRE_MESSAGE(r.code == 0, r.err);
    for (const std::string c : {"auto", "float", "double"}) {
      const std::string out = dir + "/" + name + "-" + c + ".ply";
      r = hmc_run(dir, "dec " + q(dir + "/" + name + ".hmc") + " -o " + q(out) + " --coords " + c);
      REQUIRE_MESSAGE(r.code == 0, r.err);
    }
    CHECK(coords_of(dir + "/" + name + "-float.ply") == "float");
    CHECK(coords_of(dir + "/" + name + "-double.ply") == "double");
  }
  CHECK(coords_of(dir + "/near-auto.ply") == "float");
  CHECK(coords_of(dir + "/far-auto.ply") == "double");
  // The float file of the near set re-quantizes to the same grid points as
  // the double file: the same canonical dump after re-encoding both.
  for (const std::string c : {"float", "double"}) {
    auto r = hmc_run(dir, "enc " + q(dir + "/near-" + c + ".ply") + " -o " + q(dir + "/re-" + c + ".hmc") +
                              " --bits 12 --canonical " + q(dir + "/re-" + c));
    REQUIRE_MESSAGE(r.code == 0, r.err);
  }
  CHECK(slurp(dir + "/re-float/level-0.points") == slurp(dir + "/re-double/level-0.points"));
  auto r = hmc_run(dir, "dec " + q(dir + "/near.hmc") + " -o " + q(dir + "/x.ply") + " --coords half");
  CHECK(r.code == 1);
  CHECK(r.err.find("--coords must be auto, float or double") != std::string::npos);
  CHECK(!fs::exists(dir + "/x.ply"));
}

TEST_CASE("canonical points are sorted grid integers, one per line") {
  const auto dir = testgen::temp_dir("cli_canonical");
  REQUIRE(io::write_mesh(dir + "/l.xyz", samples::lattice(3, 2, 2)).ok());
  auto r = hmc_run(dir, "enc " + q(dir + "/l.xyz") + " -o " + q(dir + "/l.hmc") + " --bits 2");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  r = hmc_run(dir, "dec " + q(dir + "/l.hmc") + " --canonical " + q(dir + "/d"));
  REQUIRE(r.code == 0);
  // The 3x2x2 lattice spans 2 units: step 2/3 on a q = 2 grid, so 0, 1, 2
  // map to 0, 1.5, 3 -> 0, 2, 3 (halves round up).
  CHECK(slurp(dir + "/d/level-0.points") ==
        "0 0 0\n0 0 2\n0 2 0\n0 2 2\n2 0 0\n2 0 2\n2 2 0\n2 2 2\n3 0 0\n3 0 2\n3 2 0\n3 2 2\n");
}

TEST_CASE("a corrupt stream exits 3 with the error class and writes nothing") {
  const auto dir = testgen::temp_dir("cli_corrupt");
  REQUIRE(io::write_mesh(dir + "/b.ply", samples::random_ball(500, 3)).ok());
  // One level: the last chunks before HEND are then the base layer's.
  REQUIRE(hmc_run(dir, "enc " + q(dir + "/b.ply") + " -o " + q(dir + "/b.hmc") + " --levels 1").code == 0);
  std::string bytes = slurp(dir + "/b.hmc");
  bytes[bytes.size() - 30] = static_cast<char>(bytes[bytes.size() - 30] ^ 0x10);
  std::ofstream(dir + "/bad.hmc", std::ios::binary) << bytes;
  auto r = hmc_run(dir, "dec " + q(dir + "/bad.hmc") + " -o " + q(dir + "/out.ply") + " --canonical " + q(dir + "/dump"));
  CHECK(r.code == 3);
  CHECK(r.err.find("crc_mismatch") != std::string::npos);
  CHECK(r.err.find("BASE") != std::string::npos);
  CHECK_FALSE(fs::exists(dir + "/out.ply"));
  CHECK_FALSE(fs::exists(dir + "/dump"));

  std::ofstream(dir + "/short.hmc", std::ios::binary) << bytes.substr(0, 60);
  r = hmc_run(dir, "dec " + q(dir + "/short.hmc"));
  CHECK(r.code == 3);
  CHECK(r.err.find("truncated") != std::string::npos);

  std::ofstream(dir + "/text.hmc") << "ply\nformat ascii 1.0\n";
  r = hmc_run(dir, "info " + q(dir + "/text.hmc"));
  CHECK(r.code == 3);
  CHECK(r.err.find("bad_magic") != std::string::npos);
}

TEST_CASE("limits: --max-points refuses a larger stream with exit 5") {
  const auto dir = testgen::temp_dir("cli_limits");
  REQUIRE(io::write_mesh(dir + "/b.ply", samples::random_ball(500, 3)).ok());
  REQUIRE(hmc_run(dir, "enc " + q(dir + "/b.ply") + " -o " + q(dir + "/b.hmc")).code == 0);
  auto r = hmc_run(dir, "dec " + q(dir + "/b.hmc") + " --max-points 100");
  CHECK(r.code == 5);
  CHECK(r.err.find("limit_exceeded") != std::string::npos);
}

TEST_CASE("--seal-box: a tile's box goes into every RCON; bad boxes are refused with nothing written") {
  const auto dir = testgen::temp_dir("cli_seal");
  REQUIRE(io::write_mesh(dir + "/t.ply", samples::torus(40, 16)).ok());
  const std::string in = q(dir + "/t.ply"), out = q(dir + "/t.hmc");
  auto r = hmc_run(dir, "enc " + in + " -o " + out + " --levels 2 --seal-box 0,0,0,2048,4096,4096");
  REQUIRE(r.code == 0);
  // Both levels decode (the decoder applies the seal it reads), and the
  // stream differs from the unsealed one only by what the seal changes.
  r = hmc_run(dir, "dec " + out + " -o " + q(dir + "/t-out.ply"));
  CHECK(r.code == 0);
  const std::string sealed = slurp(dir + "/t.hmc");
  REQUIRE(hmc_run(dir, "enc " + in + " -o " + q(dir + "/u.hmc") + " --levels 2").code == 0);
  CHECK(sealed != slurp(dir + "/u.hmc"));
  fs::remove(dir + "/t.hmc");
  for (const char* bad : {"0,0,0,2048,4096", "0,0,0,2048,4096,4097", "5,0,0,5,4096,4096", "0,0,0,1.5,4096,4096",
                          "-1,0,0,8,8,8", "a,b,c,d,e,f"}) {
    CAPTURE(bad);
    r = hmc_run(dir, "enc " + in + " -o " + out + " --seal-box " + bad);
    CHECK(r.code == 1);
    CHECK(r.err.find("--seal-box") != std::string::npos);
    CHECK_FALSE(fs::exists(dir + "/t.hmc"));
  }
  // --tolerance-diagonal: a length >= 0; the torus' own diagonal gives the
  // default stream, and bad lengths are refused with nothing written.
  REQUIRE(hmc_run(dir, "enc " + in + " -o " + out + " --levels 2 --tolerance-diagonal 0").code == 0);
  CHECK(slurp(dir + "/t.hmc") == slurp(dir + "/u.hmc"));
  fs::remove(dir + "/t.hmc");
  for (const char* bad : {"-1", "nan", "inf", "1,2", "x"}) {
    CAPTURE(bad);
    r = hmc_run(dir, "enc " + in + " -o " + out + " --tolerance-diagonal " + bad);
    CHECK(r.code == 1);
    CHECK(r.err.find("--tolerance-diagonal") != std::string::npos);
    CHECK_FALSE(fs::exists(dir + "/t.hmc"));
  }
}

TEST_CASE("bad input files exit 2 naming the problem, and leave no output") {
  const auto dir = testgen::temp_dir("cli_badinput");
  std::ofstream(dir + "/nan.xyz") << "0 0 0\n1 2 3\n4 nan 6\n";
  auto r = hmc_run(dir, "enc " + q(dir + "/nan.xyz") + " -o " + q(dir + "/o.hmc"));
  CHECK(r.code == 2);
  CHECK(r.err.find("nan.xyz:3") != std::string::npos);
  std::ofstream(dir + "/empty.xyz") << "";
  r = hmc_run(dir, "enc " + q(dir + "/empty.xyz") + " -o " + q(dir + "/o.hmc"));
  CHECK(r.code == 2);
  r = hmc_run(dir, "enc " + q(dir + "/missing.ply") + " -o " + q(dir + "/o.hmc"));
  CHECK(r.code == 2);
  r = hmc_run(dir, "enc " + q(dir + "/nan.unknown") + " -o " + q(dir + "/o.hmc"));
  CHECK(r.code == 2);
  CHECK_FALSE(fs::exists(dir + "/o.hmc"));
  CHECK(entries(dir) == 2);  // nan.xyz, empty.xyz
}

TEST_CASE("outputs: never over the input, missing directory, usage errors") {
  const auto dir = testgen::temp_dir("cli_outputs");
  REQUIRE(io::write_mesh(dir + "/s.ply", samples::uv_sphere(8, 12)).ok());
  const std::string before = slurp(dir + "/s.ply");
  auto r = hmc_run(dir, "enc " + q(dir + "/s.ply") + " -o " + q(dir + "/s.ply"));
  CHECK(r.code == 1);
  CHECK(r.err.find("overwrite the input") != std::string::npos);
  CHECK(slurp(dir + "/s.ply") == before);
  r = hmc_run(dir, "enc " + q(dir + "/s.ply") + " -o " + q(dir + "/no/such/dir/s.hmc"));
  CHECK(r.code == 4);
  CHECK(entries(dir) == 1);
  CHECK(hmc_run(dir, "enc " + q(dir + "/s.ply") + " -o x.hmc --bits 22").code == 1);
  CHECK(hmc_run(dir, "enc " + q(dir + "/s.ply") + " -o x.hmc --kind blob").code == 1);
  CHECK(hmc_run(dir, "enc " + q(dir + "/s.ply") + " -o x.hmc --frobnicate").code == 1);
  CHECK(hmc_run(dir, "enc").code == 1);
  CHECK(hmc_run(dir, "nonsense").code == 1);
  CHECK(hmc_run(dir, "help").code == 0);
  CHECK(entries(dir) == 1);
}

TEST_CASE("gen writes the samples the quick start uses") {
  const auto dir = testgen::temp_dir("cli_gen");
  auto r = hmc_run(dir, "gen torus --vertices 36450 -o " + q(dir + "/t.ply"));
  REQUIRE_MESSAGE(r.code == 0, r.err);
  auto m = io::read_mesh(dir + "/t.ply");
  REQUIRE(m.ok());
  CHECK(m.value().points.size() == 36450);
  CHECK(m.value().triangles.size() == 72900);
  CHECK(hmc_run(dir, "gen cube -o " + q(dir + "/c.ply")).code == 1);
}

TEST_CASE("quality reports the thesis' tests with stable JSON keys") {
  const auto dir = testgen::temp_dir("cli_quality");
  // A regular tetrahedron (alternate cube corners) and its four faces: every score is 1.
  Mesh m;
  m.points = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  m.tetrahedra = {{0, 1, 2, 3}};
  m.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  REQUIRE(io::write_mesh(dir + "/t.mesh", m).ok());
  auto r = hmc_run(dir, "quality " + q(dir + "/t.mesh") + " --json");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  for (const char* key : {"qt1", "qt2", "qt3", "qt4", "tri_angle", "tri_edge"}) {
    CAPTURE(key);
    const auto at = r.out.find(std::string("\"") + key + "\": ");
    REQUIRE(at != std::string::npos);
    CHECK(std::strtod(r.out.c_str() + at + std::strlen(key) + 4, nullptr) == doctest::Approx(1.0).epsilon(1e-12));
  }
  CHECK(r.out.find("\"tetrahedra\": 1") != std::string::npos);
  CHECK(hmc_run(dir, "quality " + q(dir + "/none.mesh")).code == 2);
}

TEST_CASE("quality of a stream is reported per decoded level") {
  const auto dir = testgen::temp_dir("cli_quality_stream");
  REQUIRE(io::write_mesh(dir + "/s.ply", samples::uv_sphere(12, 24)).ok());
  REQUIRE(hmc_run(dir, "enc " + q(dir + "/s.ply") + " -o " + q(dir + "/s.hmc") + " --levels 2").code == 0);
  auto r = hmc_run(dir, "quality " + q(dir + "/s.hmc") + " --json");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(r.out.find("\"level\": 1") != std::string::npos);
  CHECK(r.out.find("\"level\": 0") != std::string::npos);
  const auto at = r.out.find("\"tri_angle\": ");
  REQUIRE(at != std::string::npos);
  const double v = std::strtod(r.out.c_str() + at + 13, nullptr);
  CHECK(v > 0.3);  // a UV sphere's triangles are far from degenerate
  CHECK(v <= 1.0);
}
