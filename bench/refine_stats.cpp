// SPDX-License-Identifier: AGPL-3.0-or-later
// refine_stats: cost of coding a model as levels of detail (base layer plus
// refinement layers) against coding its finest level alone.
//
//   refine_stats [--bits Q] [--levels N] [--fraction F] [--knn K] [--seed S] FILE...
//
// For each mesh file: quantize at q bits (default 12) as the encoder does,
// then build N levels (default 4) twice: removing a random fraction F
// (default 0.3) of the points per level, and removing a spatially even
// subset of at most that fraction (a greedy independent set of the K-nearest-
// neighbour graph, K = 4 by default, in random order). The coarsest level
// goes in a base layer (encode_octree), each finer one in a refinement layer
// (encode_refinement); every layer is decoded back and checked. Prints a
// Markdown table of total bits per finest point and the ratio to the
// one-level cost, plus the parameters each refinement layer chose.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"
#include "pointset/octree.hpp"
#include "pointset/refine.hpp"

namespace {

using hmc::GridPoint;
using Points = std::vector<GridPoint>;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::uint64_t dist2(const GridPoint& a, const GridPoint& b) {
  std::uint64_t s = 0;
  for (int i = 0; i < 3; ++i) {
    const std::int64_t t = std::int64_t{a[i]} - std::int64_t{b[i]};
    s += static_cast<std::uint64_t>(t * t);
  }
  return s;
}

// k nearest neighbours of every point, by a uniform grid whose cells hold
// about two points each, searched in growing shells.
std::vector<std::vector<std::uint32_t>> knn_graph(const Points& pts, int k, int q) {
  int shift = 0;
  for (; shift < q; ++shift) {
    std::vector<std::uint64_t> cells;
    for (const auto& p : pts)
      cells.push_back((std::uint64_t{p[0] >> shift} << 42) | (std::uint64_t{p[1] >> shift} << 21) | (p[2] >> shift));
    std::sort(cells.begin(), cells.end());
    const auto distinct = static_cast<std::size_t>(std::unique(cells.begin(), cells.end()) - cells.begin());
    if (pts.size() >= 2 * distinct) break;
  }
  const auto cell_key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    return (static_cast<std::uint64_t>(x) << 42) | (static_cast<std::uint64_t>(y) << 21) | static_cast<std::uint64_t>(z);
  };
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> grid;
  for (std::uint32_t i = 0; i < pts.size(); ++i)
    grid[cell_key(pts[i][0] >> shift, pts[i][1] >> shift, pts[i][2] >> shift)].push_back(i);
  const std::int64_t cells = std::int64_t{1} << (q - shift);
  std::vector<std::vector<std::uint32_t>> nb(pts.size());
  std::vector<std::pair<std::uint64_t, std::uint32_t>> cand;
  for (std::uint32_t i = 0; i < pts.size(); ++i) {
    const std::int64_t cx = pts[i][0] >> shift, cy = pts[i][1] >> shift, cz = pts[i][2] >> shift;
    cand.clear();
    for (std::int64_t r = 0; r <= cells; ++r) {
      for (std::int64_t x = cx - r; x <= cx + r; ++x)
        for (std::int64_t y = cy - r; y <= cy + r; ++y)
          for (std::int64_t z = cz - r; z <= cz + r; ++z) {
            if (std::max({std::llabs(x - cx), std::llabs(y - cy), std::llabs(z - cz)}) != r) continue;  // shell only
            if (x < 0 || y < 0 || z < 0 || x >= cells || y >= cells || z >= cells) continue;
            const auto it = grid.find(cell_key(x, y, z));
            if (it == grid.end()) continue;
            for (std::uint32_t j : it->second)
              if (j != i) cand.emplace_back(dist2(pts[i], pts[j]), j);
          }
      // Points beyond shell r are at least r cells away.
      if (cand.size() >= static_cast<std::size_t>(k)) {
        std::sort(cand.begin(), cand.end());
        const double reach = static_cast<double>(r << shift);
        if (static_cast<double>(cand[static_cast<std::size_t>(k) - 1].first) <= reach * reach) break;
      }
    }
    for (std::size_t j = 0; j < cand.size() && j < static_cast<std::size_t>(k); ++j) nb[i].push_back(cand[j].second);
  }
  return nb;
}

// Splits `level` into the next coarser level and the points it lacks.
struct Split {
  Points coarse, added;
};

Split split_random(const Points& level, double fraction, std::mt19937_64& rng) {
  std::vector<std::uint32_t> idx(level.size());
  std::iota(idx.begin(), idx.end(), 0u);
  std::shuffle(idx.begin(), idx.end(), rng);
  const auto n_added = static_cast<std::size_t>(std::llround(fraction * static_cast<double>(level.size())));
  std::vector<char> removed(level.size(), 0);
  for (std::size_t i = 0; i < n_added; ++i) removed[idx[i]] = 1;
  Split s;
  for (std::size_t i = 0; i < level.size(); ++i) (removed[i] ? s.added : s.coarse).push_back(level[i]);
  return s;
}

Split split_even(const Points& level, double fraction, int k, int q, std::mt19937_64& rng) {
  const auto nb = knn_graph(level, k, q);
  std::vector<std::vector<std::uint32_t>> adj(level.size());
  for (std::uint32_t i = 0; i < level.size(); ++i)
    for (std::uint32_t j : nb[i]) adj[i].push_back(j), adj[j].push_back(i);
  std::vector<std::uint32_t> idx(level.size());
  std::iota(idx.begin(), idx.end(), 0u);
  std::shuffle(idx.begin(), idx.end(), rng);
  const auto limit = static_cast<std::size_t>(std::llround(fraction * static_cast<double>(level.size())));
  std::vector<char> removed(level.size(), 0), blocked(level.size(), 0);
  std::size_t count = 0;
  for (std::uint32_t i : idx) {
    if (count == limit) break;
    if (blocked[i]) continue;
    removed[i] = blocked[i] = 1;
    ++count;
    for (std::uint32_t j : adj[i]) blocked[j] = 1;
  }
  Split s;
  for (std::size_t i = 0; i < level.size(); ++i) (removed[i] ? s.added : s.coarse).push_back(level[i]);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  int bits = 12, levels = 4, knn = 4;
  double fraction = 0.3;
  std::uint64_t seed = 1;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--bits" && i + 1 < argc) bits = std::atoi(argv[++i]);
    else if (a == "--levels" && i + 1 < argc) levels = std::atoi(argv[++i]);
    else if (a == "--fraction" && i + 1 < argc) fraction = std::atof(argv[++i]);
    else if (a == "--knn" && i + 1 < argc) knn = std::atoi(argv[++i]);
    else if (a == "--seed" && i + 1 < argc) seed = std::strtoull(argv[++i], nullptr, 10);
    else files.push_back(a);
  }
  if (files.empty() || levels < 1 || bits < 1 || bits > 21 || knn < 1) {
    std::fprintf(stderr, "usage: refine_stats [--bits Q] [--levels N] [--fraction F] [--knn K] [--seed S] FILE...\n");
    return 1;
  }
  std::printf("| model | points | split | points per level (fine to coarse) | 1-level bits/pt | %d-level bits/pt | ratio | "
              "refinement bits per added point | K,L per layer | encode s | decode s |\n", levels);
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  double ratio_sum[2] = {0, 0};
  double ratio_max[2] = {0, 0};
  int count = 0;
  for (const auto& f : files) {
    auto mesh = hmc::io::read_mesh(f);
    if (!mesh) {
      std::fprintf(stderr, "%s: %s\n", f.c_str(), mesh.error().to_string().c_str());
      return 2;
    }
    hmc::EncodeOptions opts;
    opts.bits = bits;
    opts.kind = hmc::Kind::points;  // only the quantized points are needed
    opts.write_info = false;
    auto enc = hmc::encode(mesh.value(), opts);
    if (!enc) {
      std::fprintf(stderr, "%s: %s\n", f.c_str(), enc.error().to_string().c_str());
      return 2;
    }
    const Points finest = enc.value().points;
    const std::string name = f.substr(f.find_last_of('/') + 1);
    const double one = 8.0 * static_cast<double>(hmc::detail::encode_octree(finest, bits).size());
    for (int even = 0; even < 2; ++even) {
      std::mt19937_64 rng(seed);
      std::vector<Points> level{finest};
      std::vector<Points> added;
      for (int l = 1; l < levels; ++l) {
        Split s = even ? split_even(level.back(), fraction, knn, bits, rng)
                       : split_random(level.back(), fraction, rng);
        if (s.coarse.empty()) break;  // too few points for more levels
        hmc::detail::sort_canonical(s.coarse);
        level.push_back(std::move(s.coarse));
        added.push_back(std::move(s.added));
      }
      double total = 8.0 * static_cast<double>(hmc::detail::encode_octree(level.back(), bits).size());
      double enc_s = 0, dec_s = 0, refine_bits = 0, refine_points = 0;
      std::string params, sizes;
      for (std::size_t l = 0; l < level.size(); ++l) sizes += (l ? " " : "") + std::to_string(level[l].size());
      for (std::size_t l = added.size(); l-- > 0;) {
        const Points& coarse = level[l + 1];
        auto t0 = std::chrono::steady_clock::now();
        const auto bytes = hmc::detail::encode_refinement(coarse, added[l], bits);
        enc_s += seconds_since(t0);
        t0 = std::chrono::steady_clock::now();
        const Points back = hmc::detail::decode_refinement(bytes.data(), bytes.size(), bits, coarse, added[l].size());
        dec_s += seconds_since(t0);
        Points expect = added[l];
        hmc::detail::sort_canonical(expect);
        if (back != expect) {
          std::fprintf(stderr, "%s: refinement layer %zu does not round-trip\n", name.c_str(), l);
          return 3;
        }
        total += 8.0 * static_cast<double>(bytes.size());
        refine_bits += 8.0 * static_cast<double>(bytes.size());
        refine_points += static_cast<double>(added[l].size());
        if (!bytes.empty())
          params += (params.empty() ? "" : " ") + std::to_string(bytes[0] >> 4) + "," +
                    std::to_string(((bytes[0] >> 2) & 3) + 1);
      }
      const double n = static_cast<double>(finest.size());
      const double ratio = total / one;
      ratio_sum[even] += ratio;
      ratio_max[even] = std::max(ratio_max[even], ratio);
      std::printf("| %s | %zu | %s | %s | %.2f | %.2f | %.3f | %.2f | %s | %.3f | %.3f |\n", name.c_str(), finest.size(),
                  even ? "even" : "random", sizes.c_str(), one / n, total / n, ratio,
                  refine_points > 0 ? refine_bits / refine_points : 0.0, params.c_str(), enc_s, dec_s);
      std::fflush(stdout);
    }
    ++count;
  }
  if (count > 1)
    for (int even = 0; even < 2; ++even)
      std::printf("\n%s splits: mean ratio %.3f, worst %.3f over %d models\n", even ? "even" : "random",
                  ratio_sum[even] / count, ratio_max[even], count);
  return 0;
}
