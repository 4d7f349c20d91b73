// SPDX-License-Identifier: AGPL-3.0-or-later
#include "reconstruct/reconstruct.hpp"

#include <algorithm>
#include <string>

#include "util/error.hpp"
#include "util/radix_sort.hpp"
#include "util/u256.hpp"

namespace hmc::detail {

namespace {

std::uint64_t dist2(const GridPoint& a, const GridPoint& b) {
  std::uint64_t s = 0;
  for (int i = 0; i < 3; ++i) {
    const std::int64_t d = static_cast<std::int64_t>(a[i]) - static_cast<std::int64_t>(b[i]);
    s += static_cast<std::uint64_t>(d * d);
  }
  return s;
}

std::array<std::uint32_t, 3> face_of(const Tetrahedralization& dt, std::size_t t, int k) {
  const auto& tet = dt.tets[t];
  return {tet[kFaceVertices[k][0]], tet[kFaceVertices[k][1]], tet[kFaceVertices[k][2]]};
}

// Per-vertex admission limit s_v · m_class(v) (units of 1/256 squared grid).
std::vector<std::uint64_t> limits(const std::vector<std::uint64_t>& scale, const ReconParams& p) {
  std::vector<std::uint64_t> lim(scale.size());
  for (std::size_t v = 0; v < scale.size(); ++v) {
    const std::size_t c = p.vertex_class.empty() ? 0 : p.vertex_class[v];
    lim[v] = scale[v] * p.multipliers[c];
  }
  return lim;
}

bool candidate(const std::vector<GridPoint>& pts, const std::vector<std::uint64_t>& lim,
               const std::array<std::uint32_t, 3>& f) {
  for (int i = 0; i < 3; ++i) {
    const std::uint32_t u = f[i], v = f[(i + 1) % 3];
    if (256 * dist2(pts[u], pts[v]) > std::min(lim[u], lim[v])) return false;
  }
  return true;
}

}  // namespace

std::vector<std::uint64_t> local_scale(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                       std::uint32_t rank) {
  const std::size_t n = points.size();
  std::vector<std::uint64_t> keys;
  keys.reserve(dt.tets.size() * 6);
  for (const auto& t : dt.tets)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const std::uint64_t a = std::min(t[i], t[j]), b = std::max(t[i], t[j]);
        keys.push_back((a << 32) | b);
      }
  radix_sort(keys, 64);
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<std::uint32_t> start(n + 1, 0);
  for (std::uint64_t k : keys) ++start[k >> 32], ++start[k & 0xffffffffu];
  for (std::size_t v = 0, sum = 0; v <= n; ++v) {
    const std::size_t c = v < n ? start[v] : 0;
    start[v] = static_cast<std::uint32_t>(sum);
    sum += c;
  }
  std::vector<std::uint64_t> len(keys.size() * 2);
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (std::uint64_t k : keys) {
    const auto a = static_cast<std::uint32_t>(k >> 32), b = static_cast<std::uint32_t>(k & 0xffffffffu);
    const std::uint64_t d = dist2(points[a], points[b]);
    len[fill[a]++] = d;
    len[fill[b]++] = d;
  }
  std::vector<std::uint64_t> scale(n, 0);
  for (std::size_t v = 0; v < n; ++v) {
    auto b = len.begin() + start[v], e = len.begin() + start[v + 1];
    if (b == e) continue;
    const auto k = std::min<std::size_t>(rank, static_cast<std::size_t>(e - b)) - 1;
    std::nth_element(b, b + static_cast<long>(k), e);
    scale[v] = *(b + static_cast<long>(k));
  }
  return scale;
}

int compare_circumradius(const std::vector<GridPoint>& pts, const std::array<std::uint32_t, 3>& a,
                         const std::array<std::uint32_t, 3>& b) {
  // R² = |bc|²|ca|²|ab|² / (4 |u × v|²); compare N_a·D_b with N_b·D_a.
  auto parts = [&](const std::array<std::uint32_t, 3>& f, U256& num, std::uint64_t& dhi, std::uint64_t& dlo) {
    const GridPoint &p = pts[f[0]], &q = pts[f[1]], &r = pts[f[2]];
    num = U256::from(dist2(q, r)).mul(dist2(r, p)).mul(dist2(p, q));
    std::int64_t u[3], v[3];
    for (int i = 0; i < 3; ++i) {
      u[i] = static_cast<std::int64_t>(q[i]) - p[i];
      v[i] = static_cast<std::int64_t>(r[i]) - p[i];
    }
    __extension__ typedef unsigned __int128 U128;
    U128 d = 0;
    for (int i = 0; i < 3; ++i) {
      const std::int64_t c = u[(i + 1) % 3] * v[(i + 2) % 3] - u[(i + 2) % 3] * v[(i + 1) % 3];
      const auto m = static_cast<U128>(c < 0 ? -c : c);
      d += m * m;
    }
    dhi = static_cast<std::uint64_t>(d >> 64);
    dlo = static_cast<std::uint64_t>(d);
  };
  U256 na, nb;
  std::uint64_t ah, al, bh, bl;
  parts(a, na, ah, al);
  parts(b, nb, bh, bl);
  const bool inf_a = (ah | al) == 0, inf_b = (bh | bl) == 0;  // collinear: infinite radius
  if (inf_a || inf_b) return inf_a == inf_b ? 0 : (inf_a ? 1 : -1);
  return compare(na.mul(bh, bl), nb.mul(ah, al));
}

std::vector<std::uint8_t> rule_labels(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                      const std::vector<std::uint64_t>& scale, const ReconParams& p) {
  const std::size_t nt = dt.tets.size();
  const auto lim = limits(scale, p);
  std::vector<std::uint8_t> inside(nt, 1);
  // Candidate flags per (tet, local face), computed once.
  std::vector<std::uint8_t> cand(nt * 4);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) cand[t * 4 + static_cast<std::size_t>(k)] = candidate(points, lim, face_of(dt, t, k));

  // Flood from outside the hull through non-candidate faces.
  std::vector<std::uint32_t> stack;
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k)
      if (dt.neighbors[t][k] == kNoTet && !cand[t * 4 + static_cast<std::size_t>(k)] && inside[t]) {
        inside[t] = 0;
        stack.push_back(static_cast<std::uint32_t>(t));
      }
  while (!stack.empty()) {
    const std::uint32_t t = stack.back();
    stack.pop_back();
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = dt.neighbors[t][k];
      if (u == kNoTet || !inside[u] || cand[std::size_t{t} * 4 + static_cast<std::size_t>(k)]) continue;
      inside[u] = 0;
      stack.push_back(u);
    }
  }
  if (!p.peel) return inside;

  // Peeling, in rounds: an inside tetrahedron with exactly two faces exposed
  // to the outside becomes outside when the larger circumradius of its two
  // inner faces is smaller than that of its two exposed faces. All changes
  // of a round are decided on the labels at its start.
  auto exposed = [&](std::size_t t, int k) {
    const std::uint32_t u = dt.neighbors[t][k];
    return u == kNoTet || !inside[u];
  };
  auto should_peel = [&](std::size_t t) {
    if (!inside[t]) return false;
    std::array<std::uint32_t, 3> out[2], in[2];
    int no = 0, ni = 0;
    for (int k = 0; k < 4; ++k) {
      if (exposed(t, k)) {
        if (no == 2) return false;
        out[no++] = face_of(dt, t, k);
      } else {
        if (ni == 2) return false;
        in[ni++] = face_of(dt, t, k);
      }
    }
    const auto& max_in = compare_circumradius(points, in[0], in[1]) >= 0 ? in[0] : in[1];
    const auto& max_out = compare_circumradius(points, out[0], out[1]) >= 0 ? out[0] : out[1];
    return compare_circumradius(points, max_in, max_out) < 0;
  };
  std::vector<std::uint32_t> frontier, next, flips;
  std::vector<std::uint8_t> queued(nt, 0);
  for (std::size_t t = 0; t < nt; ++t)
    if (inside[t])
      for (int k = 0; k < 4; ++k)
        if (exposed(t, k)) {
          frontier.push_back(static_cast<std::uint32_t>(t));
          break;
        }
  while (!frontier.empty()) {
    flips.clear();
    for (std::uint32_t t : frontier)
      if (should_peel(t)) flips.push_back(t);
    for (std::uint32_t t : frontier) queued[t] = 0;
    for (std::uint32_t t : flips) inside[t] = 0;
    next.clear();
    for (std::uint32_t t : flips)
      for (int k = 0; k < 4; ++k) {
        const std::uint32_t u = dt.neighbors[t][k];
        if (u != kNoTet && inside[u] && !queued[u]) {
          queued[u] = 1;
          next.push_back(u);
        }
      }
    frontier.swap(next);
  }
  return inside;
}

Reconstruction extract(const Tetrahedralization& dt, Kind kind, const std::vector<std::uint8_t>& inside,
                       const ReconParams& p) {
  Reconstruction r;
  r.inside = inside;
  const std::size_t nt = dt.tets.size();
  if (kind == Kind::volume) {
    for (std::size_t t = 0; t < nt; ++t)
      if (inside[t]) r.tetrahedra.push_back(dt.tets[t]);
    return r;
  }
  if (kind != Kind::surface) return r;
  const auto& border = p.border;
  auto on_border = [&](std::uint32_t v) { return std::binary_search(border.begin(), border.end(), v); };
  auto is_dropped = [&](std::size_t t, int k) {
    return !p.drops.empty() &&
           std::binary_search(p.drops.begin(), p.drops.end(), static_cast<std::uint32_t>(4 * t + static_cast<std::size_t>(k)));
  };
  for (std::size_t t = 0; t < nt; ++t) {
    if (!inside[t]) continue;
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = dt.neighbors[t][k];
      if (u != kNoTet && inside[u]) continue;
      Triangle f = face_of(dt, t, k);
      if (!border.empty() && on_border(f[0]) && on_border(f[1]) && on_border(f[2])) continue;
      if (is_dropped(t, k)) continue;
      // Rotate so the smallest index comes first (orientation kept).
      while (f[0] > f[1] || f[0] > f[2]) f = {f[1], f[2], f[0]};
      r.triangles.push_back(f);
    }
  }
  std::sort(r.triangles.begin(), r.triangles.end());
  return r;
}

Reconstruction reconstruct(const std::vector<GridPoint>& points, const Tetrahedralization& dt, Kind kind,
                           const ReconParams& p) {
  if (kind == Kind::points) return {};
  const auto scale = local_scale(points, dt, p.scale_rank);
  auto inside = rule_labels(points, dt, scale, p);
  for (std::uint32_t t : p.toggles) {
    if (t >= inside.size()) fail(Status::bad_layer, "RCON: toggled tetrahedron " + std::to_string(t) + " does not exist");
    inside[t] ^= 1;
  }
  if (!p.drops.empty() && p.drops.back() / 4 >= inside.size())
    fail(Status::bad_layer, "RCON: dropped face " + std::to_string(p.drops.back()) + " does not exist");
  return extract(dt, kind, inside, p);
}

}  // namespace hmc::detail
