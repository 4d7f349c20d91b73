// SPDX-License-Identifier: AGPL-3.0-or-later
#include "reconstruct/reconstruct.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <iterator>
#include <string>

#include "util/error.hpp"
#include "util/u256.hpp"

namespace hmc::detail {

namespace {

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

// The squared lengths of a tetrahedron's six edges, in the order of
// TetEdgeLengths.
std::array<std::uint64_t, 6> edge_lengths(const std::vector<GridPoint>& pts, const std::array<std::uint32_t, 4>& t) {
  std::int64_t x[4][3];
  for (std::size_t i = 0; i < 4; ++i) {
    const GridPoint& p = pts[t[i]];
    for (std::size_t a = 0; a < 3; ++a) x[i][a] = p[a];
  }
  std::array<std::uint64_t, 6> out{};
  std::size_t e = 0;
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = i + 1; j < 4; ++j, ++e)
      for (std::size_t a = 0; a < 3; ++a) {
        const std::int64_t d = x[i][a] - x[j][a];
        out[e] += static_cast<std::uint64_t>(d * d);
      }
  return out;
}

// Candidate flags of the four faces of tetrahedron t (bit k: the face
// opposite vertex k): a face is a candidate when each of its edges (u, v)
// has 256·|uv|² <= min(lim[u], lim[v]). Each of the six edges is tested
// once and shared by its two faces; the four limits are read once. Here
// with the lengths given (TetEdgeLengths)...
unsigned candidate_faces(const std::array<std::uint32_t, 6>& d2, const std::vector<std::uint64_t>& lim,
                         const std::array<std::uint32_t, 4>& t) {
  const std::uint64_t l[4] = {lim[t[0]], lim[t[1]], lim[t[2]], lim[t[3]]};
  unsigned faces = 0xF;
  std::size_t e = 0;
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = i + 1; j < 4; ++j, ++e)
      if (256 * std::uint64_t{d2[e]} > std::min(l[i], l[j])) faces &= (1u << i) | (1u << j);
  return faces;
}

// ... and here without them: each length computed where it is compared
// (the decoder's one call per level; measured faster than computing the six
// first).
unsigned candidate_faces(const std::vector<GridPoint>& pts, const std::vector<std::uint64_t>& lim,
                         const std::array<std::uint32_t, 4>& t) {
  std::int64_t x[4][3];
  std::uint64_t l[4];
  for (std::size_t i = 0; i < 4; ++i) {
    const GridPoint& p = pts[t[i]];
    for (std::size_t a = 0; a < 3; ++a) x[i][a] = p[a];
    l[i] = lim[t[i]];
  }
  unsigned faces = 0xF;
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = i + 1; j < 4; ++j) {
      std::uint64_t d2 = 0;
      for (std::size_t a = 0; a < 3; ++a) {
        const std::int64_t d = x[i][a] - x[j][a];
        d2 += static_cast<std::uint64_t>(d * d);
      }
      // The edge lies on the faces opposite the other two vertices.
      if (256 * d2 > std::min(l[i], l[j])) faces &= (1u << i) | (1u << j);
    }
  return faces;
}

// The four candidate flags of a tetrahedron (bytes 0 or 1, face k at byte
// k) for each value of candidate_faces(), as the bytes of one 32-bit word.
constexpr std::array<std::array<std::uint8_t, 4>, 16> kFaceFlags = [] {
  std::array<std::array<std::uint8_t, 4>, 16> f{};
  for (std::size_t m = 0; m < 16; ++m)
    for (std::size_t k = 0; k < 4; ++k) f[m][k] = static_cast<std::uint8_t>((m >> k) & 1u);
  return f;
}();

__extension__ typedef unsigned __int128 U128;

// Below this many vertices, tetrahedra or faces, a loop is not split
// between two threads (split_range): a thread costs tens of microseconds.
constexpr std::size_t kSplitElements = 8192;

// Exact parts of a triangle: squared edge lengths e[i] (edge opposite
// vertex i) and D = |(q − p) × (r − p)|² (= 16·area²/4), so that
// R² = N / (4D) with N = e0·e1·e2 (num(), computed when needed).
struct TriangleParts {
  std::uint64_t e[3];
  U128 d;
  U256 num() const { return U256::from(e[0]).mul(e[1]).mul(e[2]); }
};

TriangleParts parts_of(const std::vector<GridPoint>& pts, const std::array<std::uint32_t, 3>& f) {
  TriangleParts t;
  const GridPoint &p = pts[f[0]], &q = pts[f[1]], &r = pts[f[2]];
  t.e[0] = dist2(q, r);
  t.e[1] = dist2(r, p);
  t.e[2] = dist2(p, q);
  std::int64_t u[3], v[3];
  for (int i = 0; i < 3; ++i) {
    u[i] = static_cast<std::int64_t>(q[i]) - p[i];
    v[i] = static_cast<std::int64_t>(r[i]) - p[i];
  }
  t.d = 0;
  for (int i = 0; i < 3; ++i) {
    const std::int64_t c = u[(i + 1) % 3] * v[(i + 2) % 3] - u[(i + 2) % 3] * v[(i + 1) % 3];
    const auto m = static_cast<U128>(c < 0 ? -c : c);
    t.d += m * m;
  }
  return t;
}

std::uint64_t hi(U128 x) { return static_cast<std::uint64_t>(x >> 64); }
std::uint64_t lo(U128 x) { return static_cast<std::uint64_t>(x); }

// R²(a) < R²(b), exactly: N_a·D_b < N_b·D_a; an infinite radius (a
// collinear triangle, D = 0) is larger than any finite one.
bool radius_less(const TriangleParts& a, const TriangleParts& b) {
  const bool ia = a.d == 0, ib = b.d == 0;
  if (ia || ib) return !ia && ib;
  return compare(a.num().mul(hi(b.d), lo(b.d)), b.num().mul(hi(a.d), lo(a.d))) < 0;
}

// A face's parts with R² as a double, which decides a comparison when the
// two differ by more than 10^-12 relatively (its own error is below
// 6·2^-53: exact edges, two roundings for N, three for D from its two
// 64-bit halves, one for the quotient); closer ones, and infinite radii
// (D = 0), go to the exact test. So the result is radius_less()'s.
struct FaceRadius {
  TriangleParts p;
  double r2;
};

FaceRadius face_radius(const std::vector<GridPoint>& pts, const std::array<std::uint32_t, 3>& f) {
  const TriangleParts t = parts_of(pts, f);
  const double n = static_cast<double>(t.e[0]) * static_cast<double>(t.e[1]) * static_cast<double>(t.e[2]);
  const double d = static_cast<double>(hi(t.d)) * 18446744073709551616.0 + static_cast<double>(lo(t.d));
  return FaceRadius{t, t.d == 0 ? 0.0 : n / d};
}

// R²(a) < R²(b), exactly.
bool radius_below(const FaceRadius& a, const FaceRadius& b) {
  if (a.p.d != 0 && b.p.d != 0) {
    if (a.r2 < b.r2 * (1 - 1e-12)) return true;
    if (a.r2 > b.r2 * (1 + 1e-12)) return false;
  }
  return radius_less(a.p, b.p);
}

// The candidate filters of spec 11.2a, applied to the faces that passed
// the edge test. `cand` is indexed by 4·tet + local face and is updated on
// both sides of every face. `memo` (FilterMemo, or null): what the neighbour
// filters (d)-(f) are computed from, reused when it was made from the same
// edge-test flags, (a)-(c) thresholds and scale, else computed into it.
void apply_filters(const std::vector<GridPoint>& pts, const Tetrahedralization& dt,
                   const std::vector<std::uint64_t>& scale, const ReconParams& p, std::vector<std::uint8_t>& cand,
                   HelperBudget* helpers, FilterMemo* memo) {
  const auto& th = p.filters;
  const std::size_t nt = dt.tets.size();
  const bool neighbours = th[kLone] || th[kNeighbourRadius] || th[kNeighbourRatio];
  const bool per_face = th[kCircleRadius] || th[kEdgeRatio] || th[kDensity];
  const std::array<std::uint32_t, 3> face_thresholds{th[kCircleRadius], th[kEdgeRatio], th[kDensity]};
  FilterMemo local;
  FilterMemo& store = memo && neighbours ? *memo : local;
  const bool reuse = &store == memo && store.valid && store.face_thresholds == face_thresholds && store.cand == cand &&
                     (!per_face || store.scale == scale);
  auto& faces = store.faces;
  auto& face_slots = store.face_slots;  // slot, twin slot (or ~0)
  auto& keep = store.keep;              // the faces that (a)-(c) keep
  auto& has = store.has;
  auto& max_r = store.max_r;
  auto& max_ratio = store.max_ratio;
  // A face's parts are recomputed from its vertices whenever they are
  // needed (a few products): storing them would cost 48 bytes per face,
  // four times the face itself, at the moment of a decoder's peak.
  auto parts = [&](std::uint32_t i) { return parts_of(pts, faces[i]); };
  if (!reuse) {
    if (&store == memo) {
      store.valid = true;
      store.face_thresholds = face_thresholds;
      store.cand = cand;
      store.scale = per_face ? scale : std::vector<std::uint64_t>{};
    }
    faces.clear();
    face_slots.clear();
    // Unique faces from the adjacency: a face is listed at the first of its
    // slots, in (tetrahedron, local face) order, with its twin slot across it.
    // Both slots of a face pass or fail the edge test together (same edges,
    // same limits), so a face whose neighbour comes first was listed there.
    // Its vertices are kept as the sorted triple. Everything below depends on
    // the faces' values, not on the order of their ids.
    for (std::size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 4; ++k) {
        const std::size_t s = t * 4 + static_cast<std::size_t>(k);
        if (!cand[s]) continue;
        const std::uint32_t u = dt.neighbors[t][k];
        if (u != kNoTet && u < t) continue;  // listed from u
        std::uint32_t twin = ~0u;
        if (u != kNoTet) {
          int m = 0;
          while (m < 3 && dt.neighbors[u][m] != t) ++m;
          twin = static_cast<std::uint32_t>(std::size_t{u} * 4 + static_cast<std::size_t>(m));
        }
        auto f = face_of(dt, t, k);
        std::sort(f.begin(), f.end());
        faces.push_back(f);
        face_slots.push_back({static_cast<std::uint32_t>(s), twin});
      }
    const std::size_t nf = faces.size();
    keep.assign(nf, 1);
    // (a) to (c) test each face on its own (none of them set: every face kept).
    if (per_face) {
      split_range(helpers, nf, kSplitElements, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
          const auto& f = faces[i];
          const TriangleParts t = parts_of(pts, f);
          const std::uint64_t smin = std::min({scale[f[0]], scale[f[1]], scale[f[2]]});
          const std::uint64_t emax = std::max({t.e[0], t.e[1], t.e[2]}), emin = std::min({t.e[0], t.e[1], t.e[2]});
          // (a) circle radius: 256·R² <= T·s, i.e. 256·N <= T·s·4D.
          if (th[kCircleRadius] &&
              compare(t.num().mul(256), U256::from(smin).mul(4ull * th[kCircleRadius]).mul(hi(t.d), lo(t.d))) > 0)
            keep[i] = 0;
          // (b) min/max edge ratio: 256·Lmin² >= T·Lmax².
          if (th[kEdgeRatio] && static_cast<U128>(emin) * 256 < static_cast<U128>(emax) * th[kEdgeRatio]) keep[i] = 0;
          // (c) density: 256·D <= T·s² (a face much larger than the local spacing squared).
          if (th[kDensity] &&
              compare(U256::from(256).mul(hi(t.d), lo(t.d)), U256::from(smin).mul(smin).mul(th[kDensity])) > 0)
            keep[i] = 0;
        }
      });
    }
    // Edge adjacency among the faces kept so far, for the neighbour filters.
    if (neighbours) {
      // A reference is the edge (a, b), a < b, and a face on it, packed as
      // a·2^(wv + wf) + b·2^wf + face when that fits in 64 bits (8 bytes, one
      // integer sort), else as three words.
      struct EdgeRef {
        std::uint32_t a, b, face;
      };
      int wv = 1, wf = 1;
      while (wv < 32 && ((pts.size() - 1) >> wv) != 0) ++wv;
      while (wf < 32 && ((nf - 1) >> wf) != 0) ++wf;
      const bool packed = 2 * wv + wf <= 64;
      std::vector<std::uint64_t> keys;
      std::vector<EdgeRef> wide;
      const auto kept = static_cast<std::size_t>(std::count(keep.begin(), keep.end(), std::uint8_t{1}));
      if (packed)
        keys.reserve(3 * kept);
      else
        wide.reserve(3 * kept);
      for (std::uint32_t i = 0; i < nf; ++i) {
        if (!keep[i]) continue;
        const auto& f = faces[i];
        for (int a = 0; a < 3; ++a)
          for (int b = a + 1; b < 3; ++b) {
            if (packed)
              keys.push_back(std::uint64_t{f[a]} << (wv + wf) | std::uint64_t{f[b]} << wf | i);
            else
              wide.push_back({f[a], f[b], i});
          }
      }
      if (packed) {
        std::sort(keys.begin(), keys.end());
      } else {
        std::sort(wide.begin(), wide.end(), [](const EdgeRef& x, const EdgeRef& y) {
          return x.a != y.a ? x.a < y.a : x.b != y.b ? x.b < y.b : x.face < y.face;
        });
      }
      const std::size_t nrefs = packed ? keys.size() : wide.size();
      auto ref = [&](std::size_t r) -> EdgeRef {
        if (!packed) return wide[r];
        const std::uint64_t x = keys[r];
        return {static_cast<std::uint32_t>(x >> (wv + wf)),
                static_cast<std::uint32_t>((x >> wf) & ((std::uint64_t{1} << wv) - 1)),
                static_cast<std::uint32_t>(x & ((std::uint64_t{1} << wf) - 1))};
      };
      // For each face: does it have a neighbour, the largest neighbour R² and
      // the largest neighbour edge ratio (as fractions compared exactly).
      has.assign(nf, 0);
      max_r.assign(nf, ~0u);
      max_ratio.assign(nf, ~0u);
      auto ratio_less = [](const TriangleParts& a, const TriangleParts& b) {  // Lmin²/Lmax² of a < of b
        const auto& x = a.e;
        const auto& y = b.e;
        const U128 xn = std::min({x[0], x[1], x[2]}), xd = std::max({x[0], x[1], x[2]});
        const U128 yn = std::min({y[0], y[1], y[2]}), yd = std::max({y[0], y[1], y[2]});
        return xn * yd < yn * xd;
      };
      std::vector<FaceRadius> group;      // the faces on one edge
      std::vector<std::uint32_t> around;  // their ids
      for (std::size_t i = 0; i < nrefs;) {
        const EdgeRef first = ref(i);
        std::size_t j = i;
        around.clear();
        for (; j < nrefs; ++j) {
          const EdgeRef e = ref(j);
          if (e.a != first.a || e.b != first.b) break;
          around.push_back(e.face);
        }
        const std::size_t g = j - i;
        if (g > 1) {
          group.clear();
          for (std::uint32_t f : around) group.push_back(face_radius(pts, faces[f]));
          // A face's best neighbour around this edge is the first largest
          // among the others: the first largest of all (r1, q1), or for that
          // face itself the first largest of the rest (r2, q2).
          std::size_t r1 = 0, q1 = 0, r2 = g, q2 = g;
          for (std::size_t b = 1; b < g; ++b) {
            if (radius_below(group[r1], group[b])) r1 = b;
            if (ratio_less(group[q1].p, group[b].p)) q1 = b;
          }
          for (std::size_t b = 0; b < g; ++b) {
            if (b != r1 && (r2 == g || radius_below(group[r2], group[b]))) r2 = b;
            if (b != q1 && (q2 == g || ratio_less(group[q2].p, group[b].p))) q2 = b;
          }
          for (std::size_t a = 0; a < g; ++a) {
            const std::uint32_t f = around[a];
            has[f] = 1;
            // Then against the best so far.
            const std::size_t br = a == r1 ? r2 : r1, bq = a == q1 ? q2 : q1;
            if (max_r[f] == ~0u || radius_below(face_radius(pts, faces[max_r[f]]), group[br])) max_r[f] = around[br];
            if (max_ratio[f] == ~0u || ratio_less(parts(max_ratio[f]), group[bq].p)) max_ratio[f] = around[bq];
          }
        }
        i = j;
      }
    }
  }
  const std::size_t nf = faces.size();
  // The faces kept in the end: keep, less those the neighbour filters drop
  // (written to a copy: a memo's keep must stay as (a)-(c) left it).
  std::vector<std::uint8_t> next;
  if (neighbours) {
    next = keep;
    split_range(helpers, nf, kSplitElements, [&](std::size_t begin, std::size_t end) {
      for (auto f = static_cast<std::uint32_t>(begin); f < end; ++f) {
        if (!keep[f]) continue;
        // (d) lone triangle: no edge shared with another kept face.
        if (th[kLone] && !has[f]) next[f] = 0;
        if (!has[f]) continue;
        const TriangleParts tf = parts(f);
        // (e) neighbour circle radius ratio: 256·R²(f) <= T·R²(g), g the
        // neighbour of largest circumradius: 256·N_f·D_g <= T·N_g·D_f.
        if (th[kNeighbourRadius]) {
          const TriangleParts tg = parts(max_r[f]);
          // A collinear neighbour (D_g = 0) has an infinite circumradius: keep.
          if (tg.d != 0 && (tf.d == 0 || compare(tf.num().mul(hi(tg.d), lo(tg.d)).mul(256),
                                                 tg.num().mul(hi(tf.d), lo(tf.d)).mul(th[kNeighbourRadius])) > 0))
            next[f] = 0;
        }
        // (f) neighbour min/max edge ratio: 256·r(f) >= T·r(h), h the
        // neighbour with the largest ratio r = Lmin²/Lmax².
        if (th[kNeighbourRatio]) {
          const TriangleParts tr = parts(max_ratio[f]);
          const auto& x = tf.e;
          const auto& y = tr.e;
          const U128 xn = std::min({x[0], x[1], x[2]}), xd = std::max({x[0], x[1], x[2]});
          const U128 yn = std::min({y[0], y[1], y[2]}), yd = std::max({y[0], y[1], y[2]});
          if (compare(U256::from(256).mul(hi(xn * yd), lo(xn * yd)),
                      U256::from(th[kNeighbourRatio]).mul(hi(yn * xd), lo(yn * xd))) < 0)
            next[f] = 0;
        }
      }
    });
  }
  const std::vector<std::uint8_t>& kept = neighbours ? next : keep;
  for (std::size_t f = 0; f < nf; ++f)
    if (!kept[f])
      for (std::uint32_t slot : face_slots[f])
        if (slot != ~0u) cand[slot] = 0;
}

// Local soundness of the interface around vertex v: 1 if v should be on it
// and is not, plus 1 per incident edge used by other than 0 or 2 faces.
// Greedy local search: flip tetrahedra around unsound vertices while that
// strictly reduces the defects of the vertices involved and keeps the
// interface's Euler characteristic (no handles or components appear).
void repair(const Tetrahedralization& dt, std::vector<std::uint8_t>& inside, const std::vector<std::uint8_t>& want) {
  const std::size_t n = want.size(), nt = dt.tets.size();
  const VertexTets by_vertex = vertex_tets(dt, n);
  const std::vector<std::uint32_t>& start = by_vertex.start;
  const std::vector<std::uint32_t>& incident = by_vertex.incident;
  DefectScratch scratch;
  // face[t]: bit k set when face k of t is on the interface, bit 4 when t
  // is inside, kept up to date by flip(). A vertex's defects then read a
  // byte per incident tetrahedron, not its neighbours' labels (most of the
  // repair's time went into those scattered reads).
  std::vector<std::uint8_t> face(nt, 0);
  for (std::uint32_t t = 0; t < nt; ++t) {
    unsigned bits = inside[t] ? 16u : 0u;
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = dt.neighbors[t][k];
      if (u == kNoTet ? inside[t] != 0 : (inside[u] != 0) != (inside[t] != 0)) bits |= 1u << k;
    }
    face[t] = static_cast<std::uint8_t>(bits);
  }
  // Inverting t's label puts each of its four faces on the interface or off
  // it, in t and in the neighbour across (where it is the face opposite the
  // neighbour's vertex that t lacks: found when needed, since few
  // tetrahedra are ever flipped; a table of them for all tetrahedra took
  // about a tenth of the repair's samples, its loads missing the cache).
  auto flip = [&](std::uint32_t t) {
    inside[t] ^= 1;
    face[t] ^= 0x1F;
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = dt.neighbors[t][k];
      if (u == kNoTet) continue;
      int j = 0;
      while (dt.neighbors[u][j] != t) ++j;
      face[u] ^= static_cast<std::uint8_t>(1u << j);
    }
  };
  // Is face k of t on the interface when t's label is `label`?
  auto face_on = [&](std::uint32_t t, int k, bool label) {
    return (((face[t] >> k) & 1u) != 0) != (label != (inside[t] != 0));
  };
  // local_defects(v), from the face bits.
  auto vertex_defects = [&](std::uint32_t v, bool* on) {
    std::vector<std::uint32_t>& ends = scratch.ends;
    ends.clear();
    for (std::uint32_t i = start[v]; i < start[v + 1]; ++i) {
      const std::uint32_t t = incident[i];
      const unsigned bits = face[t];
      if (!(bits & 16u) || !(bits & 15u)) continue;
      const auto& tet = dt.tets[t];
      for (int k = 0; k < 4; ++k) {
        if (!((bits >> k) & 1u) || tet[k] == v) continue;  // the face opposite v does not contain it
        for (int j = 0; j < 3; ++j) {
          const std::uint32_t w = tet[kFaceVertices[k][j]];
          if (w != v) ends.push_back(w);
        }
      }
    }
    return defects_of_faces(want[v] != 0, scratch, on);
  };
  // Is some face around the edge (tet[i], tet[j]) of t, other than t's own
  // two, on the interface? Walks the ring of tetrahedra around the edge
  // (both ways when the edge is on the hull).
  auto ring_on = [&](std::uint32_t t, int i, int j) {
    const auto& tet = dt.tets[t];
    const std::uint32_t a = tet[i], b = tet[j];
    int other[2], m = 0;
    for (int k = 0; k < 4; ++k)
      if (k != i && k != j) other[m++] = k;
    for (int dir = 0; dir < 2; ++dir) {
      // Cross t's face opposite other[dir]; it holds a, b and c.
      std::uint32_t prev = t, c = tet[other[1 - dir]];
      std::uint32_t x = dt.neighbors[t][other[dir]];
      while (x != t) {
        if (x == kNoTet) {
          if (prev != t && inside[prev]) return true;  // a hull face of prev
          break;
        }
        if (prev != t && (inside[prev] != 0) != (inside[x] != 0)) return true;
        const auto& xt = dt.tets[x];
        int kc = 0;
        std::uint32_t next_c = 0;
        for (int k = 0; k < 4; ++k) {
          if (xt[k] == c) kc = k;
          else if (xt[k] != a && xt[k] != b) next_c = xt[k];
        }
        prev = x;
        x = dt.neighbors[x][kc];
        c = next_c;
      }
      if (x == t) break;  // a closed ring: every face seen
    }
    return false;
  };
  // defects(v) depends only on the labels of the tetrahedra around v (a
  // face containing v lies between two of them), so it is cached, with
  // whether v is on the interface (bit 0), and recomputed only after one of
  // those flips.
  std::vector<int> cache(n, -1);
  auto state = [&](std::uint32_t v) {
    if (cache[v] < 0) {
      bool on = false;
      const int d = vertex_defects(v, &on);
      cache[v] = 2 * d + (on ? 1 : 0);
    }
    return cache[v];
  };
  auto defects = [&](std::uint32_t v) { return state(v) >> 1; };
  // Is v on the interface (some interface face contains it)? The `on` bit
  // of its state, found without the rest of the defect count.
  auto on_interface = [&](std::uint32_t v) {
    for (std::uint32_t i = start[v]; i < start[v + 1]; ++i) {
      const std::uint32_t t = incident[i];
      const unsigned bits = face[t];
      if (!(bits & 16u) || !(bits & 15u)) continue;
      for (int k = 0; k < 4; ++k)  // the face opposite v does not contain it
        if (((bits >> k) & 1u) && dt.tets[t][k] != v) return 1;
    }
    return 0;
  };
  auto around = [&](std::uint32_t t) {
    int d = 0;
    for (auto v : dt.tets[t]) d += defects(v);
    return d;
  };
  // Does the interface's Euler characteristic stay the same when t flips
  // from `from` to !from? Only t's own vertices, edges and faces can change
  // (on_before/on_after: t's vertices on the interface before and after).
  // `both`: bit k set when t's vertex k is on the interface before the flip
  // and after it.
  auto euler_kept = [&](std::uint32_t t, bool from, int on_before, int on_after, unsigned both) {
    int chi = on_after - on_before;
    for (int k = 0; k < 4; ++k) chi += face_on(t, k, !from) - face_on(t, k, from);
    // An edge of t whose own two faces go on (off) the interface leaves
    // (joins) it, -1 (+1), unless another face around it keeps it on: a
    // walk around the edge tells, unless an end of the edge is off the
    // interface before or after the flip (the other faces around the edge
    // do not change with it, so none of them is on). The walks come last,
    // and stop as soon as the edges left cannot bring chi back to 0.
    int edge[6][3], ne = 0, lo = 0, hi = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        int f[2], m = 0;
        for (int k = 0; k < 4; ++k)
          if (k != i && k != j) f[m++] = k;
        const bool before = face_on(t, f[0], from) || face_on(t, f[1], from);
        const bool after = face_on(t, f[0], !from) || face_on(t, f[1], !from);
        if (before == after) continue;  // the ring walk cannot change the answer
        const int delta = before ? 1 : -1;
        edge[ne][0] = i, edge[ne][1] = j, edge[ne][2] = delta, ++ne;
        (delta > 0 ? hi : lo) += delta;
      }
    for (int e = 0; e < ne; ++e) {
      if (chi + lo > 0 || chi + hi < 0) return false;  // 0 is out of reach
      const int delta = edge[e][2];
      (delta > 0 ? hi : lo) -= delta;
      const int i = edge[e][0], j = edge[e][1];
      if (!((both >> i) & (both >> j) & 1u) || !ring_on(t, i, j)) chi += delta;
    }
    return chi == 0;
  };
  // A try at t reads only the labels of tetrahedra incident to t's
  // vertices, all of them neighbours of v. So a vertex whose last visit
  // kept no flip fails again, try for try, unless a flip kept since then
  // touched one of its neighbours: such visits are skipped (same result,
  // far less work; most unsound vertices cannot be mended).
  std::uint64_t clock = 1;
  constexpr std::uint64_t kNever = ~std::uint64_t{0};
  std::vector<std::uint64_t> touched(n, 0), failed_at(n, kNever);
  // Likewise a try at t depends only on the labels of the tetrahedra
  // incident to t's vertices, not on the vertex being mended: a try that
  // failed fails again until a kept flip touches one of t's vertices.
  std::vector<std::uint64_t> try_failed_at(nt, kNever);
  auto same_try = [&](std::uint32_t t) {
    if (try_failed_at[t] == kNever) return false;
    for (auto w : dt.tets[t])
      if (touched[w] > try_failed_at[t]) return false;
    return true;
  };
  auto unchanged_since = [&](std::uint32_t v, std::uint64_t when) {
    for (std::uint32_t i = start[v]; i < start[v + 1]; ++i)
      for (auto w : dt.tets[incident[i]])
        if (touched[w] > when) return false;
    return true;
  };
  for (int round = 0; round < 6; ++round) {
    bool changed = false;
    for (std::uint32_t v = 0; v < n; ++v) {
      if (defects(v) == 0) continue;
      if (failed_at[v] != kNever && unchanged_since(v, failed_at[v])) continue;
      bool kept = false;
      for (std::uint32_t i = start[v]; i < start[v + 1]; ++i) {
        const std::uint32_t t = incident[i];
        if (same_try(t)) continue;
        const auto& tv = dt.tets[t];
        const int before = around(t);
        // Flipping t back restores the labels, so also the cached defects
        // of its vertices (the only ones a flip of t changes).
        const int was[4] = {cache[tv[0]], cache[tv[1]], cache[tv[2]], cache[tv[3]]};
        auto restore = [&](const int (&c)[4]) {
          for (int k = 0; k < 4; ++k) cache[tv[k]] = c[k];
        };
        const bool from = inside[t] != 0;
        int on_before = 0;
        for (int k = 0; k < 4; ++k) on_before += was[k] & 1;
        // Three tests, the cheapest first: a bound on the defects after the
        // flip from the states before it (below; it reads only labels before
        // the flip, so t is flipped after it), the Euler test, which needs
        // only whether t's vertices stay on the interface, and the defects of
        // the vertices the bound could not settle. A try is kept when all
        // pass, so the order does not change the result. Until the defects
        // are recomputed, the cached states of t's vertices describe the
        // labels before the flip, and they are right again once it is undone.
        // The states of t's vertices after the flip. Most follow from their
        // states before it without a count: the faces of F(w) are the edges
        // of w's *link* (face (w, x, y) joins x and y), so w has no defect
        // exactly when its link is one cycle, and inverting t toggles the
        // triangle xyz that t's three faces through w make in it. So a
        // vertex off the interface gets the triangle, one cycle: no defect.
        // A vertex without defects, its link a cycle C, with c of t's faces
        // through it on the interface (edges of C) before the flip:
        // c = 3: C was the triangle and the link empties; c = 2: C shortcuts
        // its path x-y-z to the edge xz, still a cycle; c = 1 (xy in C):
        // C detours x-z-y, a cycle unless z was on C (degree 4: one defect;
        // is some face around the edge (w, z), t's own two aside, on?);
        // c = 0: the triangle joins C at some corners (each then of degree 4,
        // a defect) or at none (a second fan), so at least one defect,
        // counted in full only where one would not settle the try. So do
        // the vertices with defects before.
        std::array<int, 4> now{-1, -1, -1, -1};  // state after, -1 while unknown
        int after = 0;
        for (int k = 0; k < 4; ++k) {
          if (!(was[k] & 1)) {
            now[k] = 1;
          } else if (was[k] >> 1 == 0) {
            int c = 0, on_face = 0;
            for (int j = 0; j < 4; ++j)
              if (j != k && face_on(t, j, from)) ++c, on_face = j;
            if (c == 3) now[k] = want[tv[k]] ? 2 : 0;
            else if (c == 2) now[k] = 1;
            else if (c == 1) now[k] = ring_on(t, k, on_face) ? 3 : 1;
            else after += 1;  // c = 0: at least one defect; counted below if needed
          }
          if (now[k] >= 0) after += now[k] >> 1;
        }
        if (after >= before) {
          try_failed_at[t] = clock;
          continue;
        }
        flip(t);
        int on_after = 0;
        unsigned both = 0;
        // Whether w is on the interface after the flip: bit 0 of its new
        // state where the bound found it; else w is on when one of t's faces
        // through it is an interface face after the flip; only when none is
        // (all three were before) must its other faces be looked at.
        for (int k = 0; k < 4; ++k) {
          int is_on = now[k] & 1;
          if (now[k] < 0) {
            bool on = false;
            for (int j = 0; j < 4 && !on; ++j)
              if (j != k) on = face_on(t, j, !from);
            is_on = on ? 1 : on_interface(tv[k]);
          }
          on_after += is_on;
          both |= static_cast<unsigned>(is_on & was[k] & 1) << k;
        }
        // Labels are flipped here: euler_kept reads t's label from `from`
        // only, its neighbours' from `inside`.
        if (!euler_kept(t, from, on_before, on_after, both)) {
          flip(t);
          try_failed_at[t] = clock;
          continue;
        }
        // Defects are never negative: stop counting once the sum reaches the
        // old one (the try has failed).
        for (int k = 0; k < 4 && after < before; ++k) {
          if (now[k] >= 0) continue;
          if (was[k] == 1) after -= 1;  // c = 0: its one defect counted above, now counted in full
          cache[tv[k]] = -1;
          after += defects(tv[k]);
          now[k] = cache[tv[k]];
        }
        for (int k = 0; k < 4; ++k) cache[tv[k]] = now[k];
        if (after >= before) {
          flip(t);
          restore(was);
          try_failed_at[t] = clock;
          continue;
        }
        changed = kept = true;
        ++clock;
        for (auto w : dt.tets[t]) touched[w] = clock;
        if (defects(v) == 0) break;
      }
      failed_at[v] = kept ? kNever : clock;
    }
    if (!changed) break;
  }
}

}  // namespace

VertexTets vertex_tets(const Tetrahedralization& dt, std::size_t n) {
  VertexTets out;
  out.start.assign(n + 1, 0);
  for (const auto& t : dt.tets)
    for (auto v : t) ++out.start[v + 1];
  for (std::size_t v = 0; v < n; ++v) out.start[v + 1] += out.start[v];
  out.incident.resize(out.start[n]);
  std::vector<std::uint32_t> fill(out.start.begin(), out.start.end() - 1);
  for (std::uint32_t t = 0; t < dt.tets.size(); ++t)
    for (auto v : dt.tets[t]) out.incident[fill[v]++] = t;
  return out;
}

int local_defects(const Tetrahedralization& dt, const std::vector<std::uint8_t>& inside,
                  const std::vector<std::uint32_t>& start, const std::vector<std::uint32_t>& incident,
                  const std::vector<std::uint8_t>& want, std::uint32_t v, DefectScratch& work, bool* on) {
  std::vector<std::uint32_t>& scratch = work.ends;
  // scratch holds, for each interface face around v, its other two
  // vertices (a, b) as consecutive entries.
  scratch.clear();
  for (std::uint32_t i = start[v]; i < start[v + 1]; ++i) {
    const std::uint32_t t = incident[i];
    if (!inside[t]) continue;
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = dt.neighbors[t][k];
      if (u != kNoTet && inside[u]) continue;
      const auto& tet = dt.tets[t];
      if (tet[k] == v) continue;  // the face opposite v does not contain it
      for (int j = 0; j < 3; ++j) {
        const std::uint32_t w = tet[kFaceVertices[k][j]];
        if (w != v) scratch.push_back(w);
      }
    }
  }
  return defects_of_faces(want[v] != 0, work, on);
}

int defects_of_faces(bool wanted, DefectScratch& work, bool* on) {
  const std::vector<std::uint32_t>& scratch = work.ends;
  const std::size_t faces = scratch.size() / 2;
  if (on) *on = faces > 0;
  if (faces == 0) return wanted ? 1 : 0;
  // (w, face) for both ends w of every face's edges (v, w), sorted by w.
  std::vector<std::uint64_t>& ends = work.sorted;
  ends.resize(scratch.size());
  for (std::size_t i = 0; i < scratch.size(); ++i) ends[i] = (std::uint64_t{scratch[i]} << 32) | (i / 2);
  if (ends.size() <= 48) {
    // Usually a dozen entries: insertion sort beats std::sort here.
    for (std::size_t i = 1; i < ends.size(); ++i) {
      const std::uint64_t x = ends[i];
      std::size_t j = i;
      for (; j > 0 && ends[j - 1] > x; --j) ends[j] = ends[j - 1];
      ends[j] = x;
    }
  } else {
    std::sort(ends.begin(), ends.end());
  }
  // Edges (v, w) used by other than two faces; fans: faces around v joined
  // through shared edges (v, w); more than one fan makes v a pinch point.
  std::vector<std::uint32_t>& parent = work.parent;
  parent.resize(faces);
  for (std::uint32_t f = 0; f < faces; ++f) parent[f] = f;
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  int d = 0;
  for (std::size_t i = 0; i < ends.size();) {
    std::size_t j = i + 1;
    for (; j < ends.size() && (ends[j] >> 32) == (ends[i] >> 32); ++j)
      parent[find(static_cast<std::uint32_t>(ends[j]))] = find(static_cast<std::uint32_t>(ends[i]));
    d += (j - i) != 2;
    i = j;
  }
  for (std::uint32_t f = 0; f < faces; ++f) d += find(f) == f;
  return d - 1;  // one fan is sound
}


std::vector<std::uint64_t> local_scale(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                       std::uint32_t rank, HelperBudget* helpers) {
  const std::size_t n = points.size();
  // Each vertex's distinct Delaunay neighbours, found through its
  // tetrahedra with a stamp per vertex (no global sort of the edges), and
  // the k-th smallest of their squared distances. Every edge is measured
  // from both ends.
  const VertexTets by_vertex = vertex_tets(dt, n);
  const std::vector<std::uint32_t>& start = by_vertex.start;
  const std::vector<std::uint32_t>& incident = by_vertex.incident;
  std::vector<std::uint64_t> scale(n, 0);
  split_range(helpers, n, kSplitElements, [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t> stamp(n, ~0u);  // each range its own
    std::vector<std::uint64_t> len;
    for (auto v = static_cast<std::uint32_t>(begin); v < end; ++v) {
      len.clear();
      for (std::uint32_t i = start[v]; i < start[v + 1]; ++i)
        for (auto w : dt.tets[incident[i]])
          if (w != v && stamp[w] != v) {
            stamp[w] = v;
            len.push_back(dist2(points[v], points[w]));
          }
      if (len.empty()) continue;
      const auto k = std::min<std::size_t>(rank, len.size()) - 1;
      std::nth_element(len.begin(), len.begin() + static_cast<long>(k), len.end());
      scale[v] = len[k];
    }
  });
  return scale;
}

TetEdgeLengths::TetEdgeLengths(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                               HelperBudget* helpers) {
  // Every squared length below 2^32: 3·extent² < 2^32 on the largest extent.
  std::array<std::uint32_t, 3> lo{~0u, ~0u, ~0u}, hi{0, 0, 0};
  for (const GridPoint& p : points)
    for (std::size_t a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  std::uint64_t extent = 0;
  for (std::size_t a = 0; a < 3 && !points.empty(); ++a) extent = std::max<std::uint64_t>(extent, hi[a] - lo[a]);
  if (3 * extent * extent >= (std::uint64_t{1} << 32)) return;
  d2.resize(dt.tets.size());
  split_range(helpers, dt.tets.size(), kSplitElements, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const auto e = edge_lengths(points, dt.tets[t]);
      for (std::size_t i = 0; i < 6; ++i) d2[t][i] = static_cast<std::uint32_t>(e[i]);
    }
  });
}

std::vector<std::uint8_t> candidate_flags(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                          const std::vector<std::uint64_t>& scale, const ReconParams& p,
                                          HelperBudget* helpers, FilterMemo* memo, const TetEdgeLengths* edges) {
  const std::size_t nt = dt.tets.size();
  const bool cached = edges && !edges->d2.empty();
  if (cached && edges->d2.size() != nt)
    fail(Status::internal_error, "candidate_flags: edge lengths of other tetrahedra");
  const auto lim = limits(scale, p);
  std::vector<std::uint8_t> cand(nt * 4);
  split_range(helpers, nt, kSplitElements, [&](std::size_t begin, std::size_t end) {
    if (cached)
      for (std::size_t t = begin; t < end; ++t)
        std::memcpy(cand.data() + t * 4, kFaceFlags[candidate_faces(edges->d2[t], lim, dt.tets[t])].data(), 4);
    else
      for (std::size_t t = begin; t < end; ++t)
        std::memcpy(cand.data() + t * 4, kFaceFlags[candidate_faces(points, lim, dt.tets[t])].data(), 4);
  });
  bool any_filter = false;
  for (auto f : p.filters) any_filter |= f != 0;
  if (any_filter) apply_filters(points, dt, scale, p, cand, helpers, memo);
  return cand;
}

namespace {

// The pair of a tetrahedron's faces that are exposed, by the mask of its
// exposed faces (bit k: face k): 0..5 for (0,1), (0,2), (0,3), (1,2), (1,3),
// (2,3); -1 unless exactly two are. PeelMemo's bit of each case, and its
// bit for a byte that holds the six.
constexpr std::array<int, 16> kExposedPair = {-1, -1, -1, 0, -1, 1, 3, -1, -1, 2, 4, -1, 5, -1, -1, -1};
constexpr std::uint8_t kPeelKnown = 0x40;

// Whether peeling (spec 11.4) turns tetrahedron t outside when exactly the
// two faces of `out` (mask, bit k: face k) are exposed: the larger
// circumradius of its two inner faces is smaller than that of its two
// exposed ones.
bool peel_case(const std::vector<GridPoint>& points, const std::array<std::uint32_t, 4>& t, unsigned out) {
  FaceRadius ro[2], ri[2];
  int no = 0, ni = 0;
  for (int k = 0; k < 4; ++k) {
    const std::array<std::uint32_t, 3> f{t[kFaceVertices[k][0]], t[kFaceVertices[k][1]], t[kFaceVertices[k][2]]};
    if (out & (1u << k)) ro[no++] = face_radius(points, f);
    else ri[ni++] = face_radius(points, f);
  }
  // The larger of each pair (the first on a tie, which has the same
  // radius), then strictly smaller inside.
  const FaceRadius& max_in = radius_below(ri[0], ri[1]) ? ri[1] : ri[0];
  const FaceRadius& max_out = radius_below(ro[0], ro[1]) ? ro[1] : ro[0];
  return radius_below(max_in, max_out);
}

}  // namespace

std::vector<std::uint8_t> rule_labels(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                      const std::vector<std::uint64_t>& scale, const ReconParams& p,
                                      std::vector<std::uint8_t>* cand_out, HelperBudget* helpers,
                                      FilterMemo* memo, const TetEdgeLengths* edges, PeelMemo* peel_memo) {
  const std::size_t nt = dt.tets.size();
  if (peel_memo && peel_memo->cases.size() != nt) fail(Status::internal_error, "rule_labels: peel memo of other tetrahedra");
  std::vector<std::uint8_t> inside(nt, 1);
  std::vector<std::uint8_t> own;
  std::vector<std::uint8_t>& cand = cand_out ? *cand_out : own;
  cand = candidate_flags(points, dt, scale, p, helpers, memo, edges);

  // Flood from outside the hull through non-candidate faces: the
  // tetrahedra joined to the outside (index nt) by such faces, found with a
  // union-find over the faces in tetrahedron order.
  {
    std::vector<std::uint32_t> parent(nt + 1);
    for (std::size_t t = 0; t <= nt; ++t) parent[t] = static_cast<std::uint32_t>(t);
    auto find = [&](std::uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    // With a seal (spec 0.26), a face with no vertex in the seal box does
    // not let the flood through.
    std::vector<std::uint8_t> in_seal;
    if (p.seal) {
      in_seal.resize(points.size());
      for (std::size_t v = 0; v < points.size(); ++v) in_seal[v] = in_seal_box(points[v], p.seal_box);
    }
    for (std::size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 4; ++k) {
        if (cand[t * 4 + static_cast<std::size_t>(k)]) continue;
        std::uint32_t u = dt.neighbors[t][k];
        if (u == kNoTet) u = static_cast<std::uint32_t>(nt);
        else if (u > t) continue;  // joined from u's side
        if (p.seal) {
          const auto& tet = dt.tets[t];
          if (!in_seal[tet[kFaceVertices[k][0]]] && !in_seal[tet[kFaceVertices[k][1]]] && !in_seal[tet[kFaceVertices[k][2]]])
            continue;
        }
        std::uint32_t a = find(static_cast<std::uint32_t>(t)), b = find(u);
        if (a == b) continue;
        if (a < b) std::swap(a, b);
        parent[a] = b;
      }
    const std::uint32_t out = find(static_cast<std::uint32_t>(nt));
    for (std::size_t t = 0; t < nt; ++t) inside[t] = find(static_cast<std::uint32_t>(t)) != out;
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
    unsigned out = 0;  // bit k: face k exposed
    for (int k = 0; k < 4; ++k)
      if (exposed(t, k)) out |= 1u << k;
    const int pair = kExposedPair[out];
    if (pair < 0) return false;
    if (!peel_memo) return peel_case(points, dt.tets[t], out);
    auto& known = peel_memo->cases[t];
    std::uint8_t c = known.load(std::memory_order_relaxed);
    if (!(c & kPeelKnown)) {
      c = kPeelKnown;
      for (unsigned m = 0; m < 16; ++m)
        if (kExposedPair[m] >= 0 && peel_case(points, dt.tets[t], m)) c |= static_cast<std::uint8_t>(1u << kExposedPair[m]);
      known.store(c, std::memory_order_relaxed);
    }
    return ((c >> pair) & 1u) != 0;
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

// Small components: every face-connected set of at most kBubble tetrahedra
// with one label, surrounded by the other label (and, for outside sets, not
// on the hull), takes the other label. Such sets are closed bubbles of
// surface that touch the rest at vertices at most.
constexpr std::size_t kBubble = 4;

void remove_bubbles(const Tetrahedralization& dt, std::vector<std::uint8_t>& inside) {
  const std::size_t nt = dt.tets.size();
  // seen: 0 not yet, 1 in a set of at most kBubble (or the one being
  // grown), 2 in a larger one. A set is grown only until it has more than
  // kBubble members, which are then marked 2; a later growth from another
  // member of that set meets one of them and stops too. So each growth
  // stays among a few nearby tetrahedra instead of crossing the whole
  // outside or inside, and the sets found small are the same.
  std::vector<std::uint8_t> seen(nt, 0);
  std::vector<std::uint32_t> members;
  std::vector<std::uint32_t> flips;
  for (std::size_t s0 = 0; s0 < nt; ++s0) {
    if (seen[s0]) continue;
    const std::uint8_t label = inside[s0];
    members.assign(1, static_cast<std::uint32_t>(s0));
    seen[s0] = 1;
    bool on_hull = false, large = false;
    for (std::size_t i = 0; i < members.size() && !large; ++i)
      for (int k = 0; k < 4; ++k) {
        const std::uint32_t u = dt.neighbors[members[i]][k];
        if (u == kNoTet) {
          on_hull = true;
          continue;
        }
        if (inside[u] != label) continue;
        if (seen[u] == 2 || (seen[u] == 0 && members.size() == kBubble)) {
          large = true;  // a member of a larger set, or one member too many
          break;
        }
        if (seen[u]) continue;
        seen[u] = 1;
        members.push_back(u);
      }
    if (large)
      for (auto t : members) seen[t] = 2;
    else if (label || !on_hull)
      flips.insert(flips.end(), members.begin(), members.end());
  }
  for (auto t : flips) inside[t] ^= 1;
}

void repair_search(const Tetrahedralization& dt, std::vector<std::uint8_t>& inside,
                   const std::vector<std::uint8_t>& want) {
  repair(dt, inside, want);
}

void repair_labels(const Tetrahedralization& dt, Kind kind, std::vector<std::uint8_t>& inside) {
  remove_bubbles(dt, inside);
  std::size_t n = 0;
  for (const auto& t : dt.tets)
    for (auto v : t) n = std::max<std::size_t>(n, std::size_t{v} + 1);
  const std::vector<std::uint8_t> want(n, kind == Kind::surface ? 1 : 0);
  repair(dt, inside, want);
}

Reconstruction extract(const Tetrahedralization& dt, Kind kind, const std::vector<std::uint8_t>& inside,
                       const ReconParams& p) {
  Reconstruction r;
  r.inside = inside;
  const std::size_t nt = dt.tets.size();
  if (kind == Kind::volume) {
    r.tetrahedra.reserve(static_cast<std::size_t>(std::count_if(inside.begin(), inside.end(), [](std::uint8_t x) { return x != 0; })));
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
  // Reserve for every interface face (border and drop lists remove few).
  std::size_t interface = 0;
  for (std::size_t t = 0; t < nt; ++t)
    if (inside[t])
      for (int k = 0; k < 4; ++k) interface += dt.neighbors[t][k] == kNoTet || !inside[dt.neighbors[t][k]];
  r.triangles.reserve(interface);
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

std::vector<std::uint8_t> toggle_contexts(const Tetrahedralization& dt, const std::vector<std::uint8_t>& inside,
                                          const std::vector<std::uint8_t>* cand, bool vertices) {
  const std::size_t nt = dt.tets.size();
  // The labels with one more entry, 0 (outside), at index nt, where every
  // hull face leads: a hull face of an inside tetrahedron is then a face
  // between labels like any other, and the loop below has no branch.
  std::vector<std::uint8_t> label(inside.begin(), inside.begin() + static_cast<std::ptrdiff_t>(nt));
  label.push_back(0);
  const auto past = static_cast<std::uint32_t>(nt);
  // Bit k of faces[t]: face k of t is on the interface (shared with a
  // tetrahedron of the other label, or a hull face of an inside one);
  // looked up once, for both uses below.
  std::vector<std::uint8_t> faces(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& nb = dt.neighbors[t];
    const std::uint8_t own = label[t];
    unsigned m = 0;
    for (int k = 0; k < 4; ++k) m |= static_cast<unsigned>(label[std::min(nb[k], past)] != own) << k;
    faces[t] = static_cast<std::uint8_t>(m);
  }
  // Points on the interface (spec 11.4a), when the contexts need them.
  std::vector<std::uint8_t> on;
  if (vertices) {
    // One past the largest vertex index (a loop that vectorizes).
    const std::uint32_t* index = dt.tets.empty() ? nullptr : dt.tets[0].data();
    std::uint32_t top = 0;
    for (std::size_t i = 0; i < 4 * nt; ++i) top = std::max(top, index[i]);
    on.assign(nt ? std::size_t{top} + 1 : 0, 0);
    for (std::size_t t = 0; t < nt; ++t)
      for (unsigned m = faces[t]; m != 0; m &= m - 1) {
        const int k = __builtin_ctz(m);
        for (int j = 0; j < 3; ++j) on[dt.tets[t][kFaceVertices[k][j]]] = 1;
      }
  }
  static constexpr std::uint8_t kOnFaces[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 3};  // min(3, set bits)
  std::vector<std::uint8_t> ctx(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    unsigned c = 4u * label[t] + kOnFaces[faces[t]];
    if (cand) {
      // Four flags of 0 or 1, one byte each: their sum is the top byte of
      // the word times 0x01010101.
      std::uint32_t w;
      std::memcpy(&w, cand->data() + 4 * t, 4);
      c += kLabelContexts * ((w * 0x01010101u) >> 24);
    }
    if (vertices) {
      const auto& T = dt.tets[t];
      if (on[T[0]] & on[T[1]] & on[T[2]] & on[T[3]]) c += kCandidateContexts;
    }
    ctx[t] = static_cast<std::uint8_t>(c);
  }
  return ctx;
}

namespace {

// The neighbour context of tetrahedron t (spec 11.5, flag bit 7): 3 times
// its context of the 80, plus how many of its face neighbours of smaller
// index are toggled (`flipped`, decided for every tetrahedron before t),
// at most 2. A hull face leads to kNoTet, above every index.
std::size_t neighbour_context(const Tetrahedralization& dt, const std::vector<std::uint8_t>& ctx,
                              const std::vector<std::uint8_t>& flipped, std::size_t t) {
  unsigned a = 0;
  for (std::uint32_t u : dt.neighbors[t]) a += u < t ? flipped[u] : 0u;
  return 3 * std::size_t{ctx[t]} + std::min(a, 2u);
}

}  // namespace

std::array<std::vector<std::uint32_t>, kToggleContexts> toggle_ranks(const Tetrahedralization& dt,
                                                                     const std::vector<std::uint8_t>& inside,
                                                                     const std::vector<std::uint32_t>& toggled,
                                                                     const std::vector<std::uint8_t>* cand,
                                                                     bool vertices) {
  return std::move(toggle_ranks(toggle_contexts(dt, inside, cand, vertices), toggled)[2]);
}

std::array<ToggleRanks, 3> toggle_ranks(const std::vector<std::uint8_t>& ctx, const std::vector<std::uint32_t>& toggled) {
  // A toggled tetrahedron's rank among the contexts c mod m is the sum of
  // the counts so far of the (kToggleContexts) contexts congruent to c.
  static constexpr int kCounts[3] = {kLabelContexts, kCandidateContexts, kToggleContexts};
  std::array<ToggleRanks, 3> ranks;
  std::array<std::uint32_t, kToggleContexts> seen{};
  std::size_t next = 0;
  for (std::size_t t = 0; t < ctx.size(); ++t) {
    const int c = ctx[t];
    if (next < toggled.size() && toggled[next] == t) {
      for (std::size_t i = 0; i < 3; ++i) {
        std::uint32_t rank = 0;
        for (int same = c % kCounts[i]; same < kToggleContexts; same += kCounts[i])
          rank += seen[static_cast<std::size_t>(same)];
        ranks[i][static_cast<std::size_t>(c % kCounts[i])].push_back(rank);
      }
      ++next;
    }
    ++seen[static_cast<std::size_t>(c)];
  }
  return ranks;
}

NeighbourRanks neighbour_ranks(const Tetrahedralization& dt, const std::vector<std::uint8_t>& ctx,
                               const std::vector<std::uint32_t>& toggled) {
  const std::size_t nt = ctx.size();
  std::vector<std::uint8_t> flipped(nt, 0);
  for (std::uint32_t t : toggled) flipped[t] = 1;
  NeighbourRanks out;
  out.ranks.resize(kNeighbourContexts);
  out.sizes.assign(kNeighbourContexts, 0);
  for (std::size_t t = 0; t < nt; ++t) {
    const std::size_t j = neighbour_context(dt, ctx, flipped, t);
    if (flipped[t]) out.ranks[j].push_back(out.sizes[j]);
    ++out.sizes[j];
  }
  return out;
}

std::size_t toggle_count(const ReconParams& p) {
  std::size_t n = p.toggles.size();
  for (const auto& r : p.toggle_ranks) n += r.size();
  for (const auto& r : p.neighbour_lists) n += r.size();
  return n;
}

void apply_toggles(const Tetrahedralization& dt, const ReconParams& p, std::vector<std::uint8_t>& inside,
                   const std::vector<std::uint8_t>* cand) {
  for (std::uint32_t t : p.toggles) {
    if (t >= inside.size()) fail(Status::bad_layer, "RCON: toggled tetrahedron " + std::to_string(t) + " does not exist");
  }
  std::vector<std::uint32_t> flip(p.toggles);
  // Contexts cost a pass over the tetrahedra: only when some list can toggle
  // (an inverted list of the neighbour contexts toggles even when empty).
  const bool neighbours = p.neighbour_contexts;
  if (p.compact &&
      (neighbours || std::any_of(p.toggle_ranks.begin(), p.toggle_ranks.end(), [](const auto& r) { return !r.empty(); }))) {
    // All ranks refer to the labels before any toggle.
    if (neighbours && (!p.vertex_contexts || !p.candidate_contexts || p.neighbour_lists.size() != kNeighbourContexts ||
                       p.neighbour_inverted.size() != kNeighbourContexts))
      fail(Status::internal_error, "apply_toggles: neighbour contexts need vertex contexts and their lists");
    if (p.candidate_contexts && (!cand || cand->size() != 4 * inside.size()))
      fail(Status::internal_error, "apply_toggles: candidate contexts need the candidate flags");
    const auto ctx = toggle_contexts(dt, inside, p.candidate_contexts ? cand : nullptr, p.vertex_contexts);
    // A neighbour context depends on the toggles of the tetrahedra before
    // it: the walk in ascending index decides them in turn.
    const std::vector<std::uint32_t>* lists = neighbours ? p.neighbour_lists.data() : p.toggle_ranks.data();
    const int contexts = neighbours ? kNeighbourContexts : kToggleContexts;
    std::vector<std::uint8_t> flipped(neighbours ? ctx.size() : 0, 0);
    std::array<std::uint32_t, kNeighbourContexts> seen{};
    std::array<std::size_t, kNeighbourContexts> next{};
    for (std::size_t t = 0; t < ctx.size(); ++t) {
      const std::size_t j = neighbours ? neighbour_context(dt, ctx, flipped, t) : ctx[t];
      const bool listed = next[j] < lists[j].size() && lists[j][next[j]] == seen[j];
      next[j] += listed;
      ++seen[j];
      if (listed != (neighbours && p.neighbour_inverted[j] != 0)) {
        flip.push_back(static_cast<std::uint32_t>(t));
        if (neighbours) flipped[t] = 1;
      }
    }
    for (int j = 0; j < contexts; ++j)
      if (next[j] < lists[j].size())
        fail(Status::bad_layer, "RCON: toggle rank " + std::to_string(lists[j][next[j]]) + " of context " +
                                    std::to_string(j) + " names no tetrahedron (the context has " +
                                    std::to_string(seen[j]) + ")");
  }
  for (std::uint32_t t : flip) inside[t] ^= 1;
}

std::vector<std::uint32_t> inherited_border(const std::vector<GridPoint>& points, const std::vector<GridPoint>& coarse,
                                            const std::vector<std::uint32_t>& coarse_border) {
  std::vector<std::uint32_t> out;
  out.reserve(coarse_border.size());
  auto from = points.begin();  // both lists ascend, so each search starts at the last hit
  for (std::uint32_t i : coarse_border) {
    if (i >= coarse.size()) fail(Status::internal_error, "inherited border index out of range");
    from = std::lower_bound(from, points.end(), coarse[i]);
    if (from == points.end() || *from != coarse[i])
      fail(Status::internal_error, "a coarser level's border point is missing from the finer level");
    out.push_back(static_cast<std::uint32_t>(from - points.begin()));
  }
  return out;
}

std::vector<std::uint32_t> border_change(const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b) {
  std::vector<std::uint32_t> out;
  out.reserve(a.size() + b.size());
  std::set_symmetric_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

void resolve_border(ReconParams& p, const std::vector<std::uint32_t>& inherited) {
  if (!p.border_delta) return;
  p.border = border_change(p.border, inherited);
  p.border_delta = false;
}

Reconstruction reconstruct(const std::vector<GridPoint>& points, const Tetrahedralization& dt, Kind kind,
                           const ReconParams& p, HelperBudget* helpers) {
  if (kind == Kind::points) return {};
  if (p.border_delta) fail(Status::internal_error, "reconstruct: the border list is not resolved");
  const auto scale = local_scale(points, dt, p.scale_rank, helpers);
  std::vector<std::uint8_t> cand;
  auto inside = rule_labels(points, dt, scale, p, &cand, helpers);
  if (p.repair) repair_labels(dt, kind, inside);
  return reconstruct_from_labels(dt, kind, p, std::move(inside), &cand);
}

Reconstruction reconstruct_from_labels(const Tetrahedralization& dt, Kind kind, const ReconParams& p,
                                       std::vector<std::uint8_t> inside, const std::vector<std::uint8_t>* cand) {
  if (kind == Kind::points) return {};
  if (p.border_delta) fail(Status::internal_error, "reconstruct: the border list is not resolved");
  if (inside.size() != dt.tets.size()) fail(Status::internal_error, "reconstruct: one label per tetrahedron needed");
  apply_toggles(dt, p, inside, cand);
  if (!p.drops.empty() && p.drops.back() / 4 >= inside.size())
    fail(Status::bad_layer, "RCON: dropped face " + std::to_string(p.drops.back()) + " does not exist");
  return extract(dt, kind, inside, p);
}

}  // namespace hmc::detail
