// SPDX-License-Identifier: AGPL-3.0-or-later
// delaunay_stats: the canonical Delaunay layer on real models.
//
//   delaunay_stats [--bits Q] [--no-check] [--native] FILE...
//
// For each mesh file: quantize at q bits (default 12) as the encoder does,
// then report the number of points and tetrahedra, how many tetrahedra
// depend on the tie-break (they have an interior face whose unperturbed
// in-sphere test is exactly zero), the time of delaunay() (TetGen plus the
// library's own certificate) per 100k points, the share of that spent
// outside TetGen, and the independent checker's verdict (tests/support).
// --native also times the native backend and reports whether its
// tetrahedra coincide with TetGen's (they must: one rule, two codes).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "delaunay/adjacency.hpp"
#include "delaunay/delaunay.hpp"
#include "delaunay/predicates.hpp"
#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"
#include "support/delaunay_checker.hpp"

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace hmc;
  using namespace hmc::detail;
  int bits = 12;
  bool check = true, native = false;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--bits" && i + 1 < argc) bits = std::atoi(argv[++i]);
    else if (a == "--no-check") check = false;
    else if (a == "--native") native = true;
    else files.push_back(a);
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: delaunay_stats [--bits Q] [--no-check] [--native] FILE...\n");
    return 1;
  }
  std::printf("| model | q | points | tets | tie tets | tie faces | delaunay() s/100k pts | TetGen s/100k pts | "
              "certificate share | checker |%s\n", native ? " native s/100k pts | native = TetGen |" : "");
  std::printf("|---|---|---|---|---|---|---|---|---|---|%s\n", native ? "---|---|" : "");
  for (const auto& f : files) {
    auto mesh = io::read_mesh(f);
    if (!mesh) {
      std::fprintf(stderr, "%s: %s\n", f.c_str(), mesh.error().to_string().c_str());
      return 2;
    }
    EncodeOptions o;
    o.bits = bits;
    auto enc = encode(mesh.value(), o);
    if (!enc) {
      std::fprintf(stderr, "%s: %s\n", f.c_str(), enc.error().to_string().c_str());
      return 2;
    }
    const auto& pts = enc.value().points;

    auto t0 = std::chrono::steady_clock::now();
    const Tetrahedralization dt = delaunay(pts);
    const double t_total = seconds_since(t0);

    // TetGen alone (first attempt), for the share of the certificate.
    std::vector<std::array<std::uint32_t, 4>> raw, raw_nb;
    t0 = std::chrono::steady_clock::now();
    const bool tetgen_used = backend::tetgen(pts, raw, raw_nb);
    const double t_tetgen = tetgen_used ? seconds_since(t0) : 0.0;

    // Tie-dependence with the library's (fast) predicates.
    std::vector<char> tie(dt.tets.size(), 0);
    std::size_t tie_faces = 0;
    for (std::size_t t = 0; t < dt.tets.size(); ++t)
      for (int k = 0; k < 4; ++k) {
        const auto u = dt.neighbors[t][k];
        if (u == kNoTet || u < t) continue;
        const auto& T = dt.tets[t];
        const auto& e = pts[dt.tets[u][0] + dt.tets[u][1] + dt.tets[u][2] + dt.tets[u][3] - (T[0] + T[1] + T[2] + T[3] - T[k])];
        if (insphere(pts[T[0]], pts[T[1]], pts[T[2]], pts[T[3]], e) == 0) {
          ++tie_faces;
          tie[t] = tie[u] = 1;
        }
      }
    std::size_t tie_tets = 0;
    for (char c : tie) tie_tets += static_cast<std::size_t>(c);

    std::string verdict = "skipped";
    if (check) {
      const auto rep = check::check_delaunay(pts, dt.tets, true);
      verdict = rep.ok ? "ok" : "FAIL: " + rep.error;
      if (rep.ok && rep.tie_tets != tie_tets) verdict = "ok (tie count differs!)";
    }
    std::string agree;
    if (native) {
      std::vector<std::array<std::uint32_t, 4>> other, other_nb;
      t0 = std::chrono::steady_clock::now();
      backend::native(pts, other, other_nb);
      const double t_native = seconds_since(t0);
      for (auto& t : other) canonicalize_tet(pts, t);
      std::sort(other.begin(), other.end());
      char buf[64];
      std::snprintf(buf, sizeof buf, " %.3f | %s |", t_native * 1e5 / static_cast<double>(pts.size()),
                    other == dt.tets ? "yes" : "NO");
      agree = buf;
    }
    const auto name = f.substr(f.find_last_of('/') + 1);
    const double per = 1e5 / static_cast<double>(pts.size());
    char tg[64] = "not used (extent >= 2^16)", share[32] = "-";
    if (tetgen_used) {
      std::snprintf(tg, sizeof tg, "%.3f", t_tetgen * per);
      std::snprintf(share, sizeof share, "%.0f%%", 100.0 * (t_total - t_tetgen) / t_total);
    }
    std::printf("| %s | %d | %zu | %zu | %zu (%.2f%%) | %zu | %.3f | %s | %s | %s |%s\n", name.c_str(), bits,
                pts.size(), dt.tets.size(), tie_tets, 100.0 * static_cast<double>(tie_tets) / static_cast<double>(dt.tets.size()),
                tie_faces, t_total * per, tg, share, verdict.c_str(), agree.c_str());
    std::fflush(stdout);
  }
  return 0;
}
