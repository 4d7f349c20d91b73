// SPDX-License-Identifier: AGPL-3.0-or-later
#include "pointset/anchored_vq.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <unordered_set>

#include "entropy/huffman.hpp"
#include "pointset/octree.hpp"
#include "quant/vector_quantizer.hpp"
#include "util/error.hpp"
#include "util/kdtree.hpp"

namespace hmc::detail {

namespace {

const char* const kWhat = "refinement layer (anchored VQ)";
constexpr std::uint32_t kAlphabet = 64;  // gap and residual symbols; the last one escapes
constexpr std::uint32_t kEscape = kAlphabet - 1;
constexpr std::uint64_t kMaxStep = (std::uint64_t{1} << 21) - 1;
constexpr int kMaxAnchors = 16;

using IPoint = KdTree<std::int64_t>::Point;

IPoint to_ipoint(const GridPoint& p) { return {std::int64_t{p[0]}, std::int64_t{p[1]}, std::int64_t{p[2]}}; }

std::uint64_t pack(const IPoint& p) {
  return (static_cast<std::uint64_t>(p[0]) << 42) | (static_cast<std::uint64_t>(p[1]) << 21) |
         static_cast<std::uint64_t>(p[2]);
}

std::uint64_t zigzag(std::int64_t r) {
  return r >= 0 ? static_cast<std::uint64_t>(r) << 1 : (static_cast<std::uint64_t>(-(r + 1)) << 1) | 1u;
}

std::int64_t unzigzag(std::uint64_t z) {
  return (z & 1u) ? -static_cast<std::int64_t>(z >> 1) - 1 : static_cast<std::int64_t>(z >> 1);
}

// A value as a symbol below kEscape, or kEscape followed by ue(value - kEscape).
void put_escaped(BitWriter& w, const HuffmanCode& code, std::uint64_t v) {
  code.encode(w, static_cast<std::uint32_t>(std::min<std::uint64_t>(v, kEscape)));
  if (v >= kEscape) w.exp_golomb(static_cast<std::uint32_t>(v - kEscape));
}

std::uint64_t get_escaped(BitReader& r, const HuffmanCode& code) {
  const std::uint64_t v = code.decode(r);
  return v == kEscape ? kEscape + r.exp_golomb() : v;
}

std::int64_t clamp_grid(std::int64_t v, int q) { return std::clamp<std::int64_t>(v, 0, (std::int64_t{1} << q) - 1); }

// floor(d / s + 1/2) for s >= 1.
std::int64_t round_div(std::int64_t d, std::int64_t s) {
  const std::int64_t n = 2 * d + s, m = 2 * s;
  return n >= 0 ? n / m : -((-n + m - 1) / m);
}

std::vector<GridPoint> canonical_copy(const std::vector<GridPoint>& pts) {
  std::vector<GridPoint> c = pts;
  sort_canonical(c);
  return c;
}

void check_points(const std::vector<GridPoint>& pts, int q, const char* name) {
  for (const GridPoint& p : pts)
    if ((p[0] | p[1] | p[2]) >> q)
      fail(Status::invalid_argument, std::string(kWhat) + ": a " + name + " point lies outside the grid");
  for (std::size_t i = 1; i < pts.size(); ++i)
    if (!(pts[i - 1] < pts[i]))
      fail(Status::invalid_argument, std::string(kWhat) + ": " + name + " points are not distinct");
}

// The codeword nearest to `target` (ties to the lower index), with the exact
// squared error of the prediction.
struct CodeChoice {
  std::int64_t error2 = 0;
  std::uint32_t anchor = 0, code = 0;
};

class Predictor {
 public:
  Predictor(const std::vector<GridPoint>& coarse, const VectorQuantizer& vq, int anchors)
      : coarse_(coarse.size()), anchors_(std::clamp(anchors, 1, kMaxAnchors)) {
    for (std::size_t i = 0; i < coarse.size(); ++i) coarse_[i] = to_ipoint(coarse[i]);
    coarse_tree_ = KdTree<std::int64_t>(coarse_);
    std::vector<VqVector> cb(vq.codebook.size());
    for (std::size_t j = 0; j < cb.size(); ++j)
      cb[j] = {double(vq.codebook[j][0]), double(vq.codebook[j][1]), double(vq.codebook[j][2])};
    code_tree_ = codebook_tree(cb);
    for (const auto& e : vq.codebook) codes_.push_back({e[0], e[1], e[2]});
  }

  /// The best (anchor, codeword) for p among its nearest coarse points:
  /// smallest prediction error, then smaller anchor index, then smaller code.
  CodeChoice best(const IPoint& p) const {
    KdTree<std::int64_t>::Hit hits[kMaxAnchors];
    const int n = coarse_tree_.nearest(p, anchors_, hits);
    CodeChoice best{-1, 0, 0};
    for (int h = 0; h < n; ++h) {
      const IPoint& a = coarse_[hits[h].index];
      const VqVector t{double(p[0] - a[0]), double(p[1] - a[1]), double(p[2] - a[2])};
      const std::uint32_t code = code_tree_.nearest(t).index;
      const std::int64_t e = error2(p, a, code);
      const CodeChoice c{e, hits[h].index, code};
      if (best.error2 < 0 || std::tie(c.error2, c.anchor, c.code) < std::tie(best.error2, best.anchor, best.code))
        best = c;
    }
    return best;
  }

  /// The candidate anchors of p.
  int anchors_of(const IPoint& p, std::uint32_t* out) const {
    KdTree<std::int64_t>::Hit hits[kMaxAnchors];
    const int n = coarse_tree_.nearest(p, anchors_, hits);
    for (int h = 0; h < n; ++h) out[h] = hits[h].index;
    return n;
  }

  std::int64_t error2(const IPoint& p, const IPoint& a, std::uint32_t code) const {
    std::int64_t e = 0;
    for (std::size_t c = 0; c < 3; ++c) {
      const std::int64_t d = p[c] - a[c] - codes_[code][c];
      e += d * d;
    }
    return e;
  }

  const IPoint& coarse(std::uint32_t i) const { return coarse_[i]; }
  const IPoint& code(std::uint32_t i) const { return codes_[i]; }
  std::uint32_t code_count() const { return static_cast<std::uint32_t>(codes_.size()); }

 private:
  std::vector<IPoint> coarse_;
  int anchors_;
  KdTree<std::int64_t> coarse_tree_;
  KdTree<double> code_tree_;
  std::vector<IPoint> codes_;
};

struct Coded {
  std::uint32_t anchor, code;
  std::array<std::uint64_t, 3> z;  // zigzagged residuals (0 without residual)
  bool operator<(const Coded& o) const { return std::tie(anchor, code, z) < std::tie(o.anchor, o.code, o.z); }
};

}  // namespace

VqLayer encode_vq_layer(const std::vector<GridPoint>& coarse_in, const std::vector<GridPoint>& added_in,
                        const VectorQuantizer& vq, int q, const VqLayerOptions& options) {
  if (q < 1 || q > 21) fail(Status::invalid_argument, std::string(kWhat) + ": q must be 1..21");
  if (vq.codebook.empty() || vq.codebook.size() > 65536)
    fail(Status::invalid_argument, std::string(kWhat) + ": codebook size must be 1..65536");
  if (options.step > kMaxStep) fail(Status::invalid_argument, std::string(kWhat) + ": residual step above 2^21 - 1");
  const std::vector<GridPoint> coarse = canonical_copy(coarse_in);
  check_points(coarse, q, "coarse");
  if (coarse.empty()) fail(Status::invalid_argument, std::string(kWhat) + ": the coarse level is empty");
  // Process the added points in canonical order, so that the result does
  // not depend on the order they were given in.
  std::vector<std::uint32_t> order(added_in.size());
  for (std::uint32_t j = 0; j < order.size(); ++j) order[j] = j;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return added_in[a] < added_in[b]; });
  for (std::size_t j = 1; j < order.size(); ++j)
    if (added_in[order[j - 1]] == added_in[order[j]])
      fail(Status::invalid_argument, std::string(kWhat) + ": added points are not distinct");

  const Predictor pred(coarse, vq, options.anchors);
  const auto s = static_cast<std::int64_t>(options.step);
  std::unordered_set<std::uint64_t> occupied;
  occupied.reserve(2 * (coarse.size() + added_in.size()));
  for (const GridPoint& c : coarse) occupied.insert(pack(to_ipoint(c)));
  // An added point may coincide with a coarse point: when the coarser level
  // was itself coded lossily, one of its points can land on an input point
  // of this layer. Such a point is coded like any other; since its own
  // position is taken, it goes to the nearest free placement (or is dropped).
  for (const GridPoint& a : added_in)
    if ((a[0] | a[1] | a[2]) >> q) fail(Status::invalid_argument, std::string(kWhat) + ": an added point lies outside the grid");

  // Where (anchor, code, residual r) puts a point.
  auto place = [&](std::uint32_t anchor, std::uint32_t code, const std::array<std::int64_t, 3>& r) {
    IPoint x{};
    for (std::size_t c = 0; c < 3; ++c)
      x[c] = clamp_grid(pred.coarse(anchor)[c] + pred.code(code)[c] + s * r[c], q);
    return x;
  };
  auto residual = [&](const IPoint& p, std::uint32_t anchor, std::uint32_t code) {
    std::array<std::int64_t, 3> r{0, 0, 0};
    if (s > 0)
      for (std::size_t c = 0; c < 3; ++c) r[c] = round_div(p[c] - pred.coarse(anchor)[c] - pred.code(code)[c], s);
    return r;
  };
  auto dist2 = [](const IPoint& a, const IPoint& b) { return KdTree<std::int64_t>::distance2(a, b); };

  VqLayer out;
  out.decoded.resize(added_in.size());
  out.kept.assign(added_in.size(), 1);
  std::vector<Coded> coded;
  coded.reserve(added_in.size());
  for (std::uint32_t j : order) {
    const IPoint p = to_ipoint(added_in[j]);
    const CodeChoice choice = pred.best(p);
    std::uint32_t anchor = choice.anchor, code = choice.code;
    std::array<std::int64_t, 3> r = residual(p, anchor, code);
    IPoint x = place(anchor, code, r);
    if (occupied.count(pack(x))) {
      // The best code lands on a point already there: take the nearest free
      // placement over every candidate anchor, codeword and, with a
      // residual, the residuals next to the rounded one.
      std::uint32_t anchors[kMaxAnchors];
      const int na = pred.anchors_of(p, anchors);
      bool found = false;
      std::tuple<std::int64_t, std::int64_t, std::uint32_t, std::uint32_t, int> best_key{};
      for (int h = 0; h < na; ++h)
        for (std::uint32_t k = 0; k < pred.code_count(); ++k) {
          const std::array<std::int64_t, 3> r0 = residual(p, anchors[h], k);
          const int variations = s > 0 ? 27 : 1;
          for (int v = 0; v < variations; ++v) {
            std::array<std::int64_t, 3> rv = r0;
            if (s > 0) rv[0] += v / 9 - 1, rv[1] += (v / 3) % 3 - 1, rv[2] += v % 3 - 1;
            const IPoint xv = place(anchors[h], k, rv);
            if (occupied.count(pack(xv))) continue;
            const auto key = std::make_tuple(dist2(p, xv), pred.error2(p, pred.coarse(anchors[h]), k), anchors[h], k, v);
            if (!found || key < best_key) {
              found = true;
              best_key = key;
              anchor = anchors[h], code = k, r = rv, x = xv;
            }
          }
        }
      if (!found) {
        out.kept[j] = 0;
        ++out.dropped;
        continue;
      }
      ++out.displaced;
    }
    occupied.insert(pack(x));
    out.decoded[j] = {static_cast<std::uint32_t>(x[0]), static_cast<std::uint32_t>(x[1]), static_cast<std::uint32_t>(x[2])};
    const double e2 = static_cast<double>(dist2(p, x));
    out.max_error = std::max(out.max_error, std::sqrt(e2));
    out.sum_error2 += e2;
    coded.push_back({anchor, code, {zigzag(r[0]), zigzag(r[1]), zigzag(r[2])}});
  }
  if (coded.empty()) return out;  // every point dropped: the caller drops the layer
  std::sort(coded.begin(), coded.end());

  std::vector<std::uint64_t> gap_freq(kAlphabet, 0), code_freq(vq.codebook.size(), 0);
  std::array<std::vector<std::uint64_t>, 3> res_freq;
  for (auto& f : res_freq) f.assign(kAlphabet, 0);
  std::uint32_t prev = 0;
  for (const Coded& c : coded) {
    ++gap_freq[std::min<std::uint64_t>(c.anchor - prev, kEscape)];
    prev = c.anchor;
    ++code_freq[c.code];
    for (std::size_t a = 0; a < 3; ++a) ++res_freq[a][std::min<std::uint64_t>(c.z[a], kEscape)];
  }
  const HuffmanCode gap_code = HuffmanCode::from_frequencies(gap_freq);
  const HuffmanCode index_code = HuffmanCode::from_frequencies(code_freq);
  std::array<HuffmanCode, 3> res_code;
  BitWriter w;
  w.exp_golomb(options.step);
  gap_code.write(w);
  index_code.write(w);
  if (s > 0)
    for (std::size_t a = 0; a < 3; ++a) {
      res_code[a] = HuffmanCode::from_frequencies(res_freq[a]);
      res_code[a].write(w);
    }
  prev = 0;
  for (const Coded& c : coded) {
    put_escaped(w, gap_code, c.anchor - prev);
    prev = c.anchor;
    index_code.encode(w, c.code);
    if (s > 0)
      for (std::size_t a = 0; a < 3; ++a) put_escaped(w, res_code[a], c.z[a]);
  }
  out.bytes = w.finish();
  return out;
}

std::vector<GridPoint> decode_vq_layer(const std::uint8_t* data, std::size_t size, int q,
                                       const std::vector<GridPoint>& coarse, const VectorQuantizer& vq,
                                       std::uint64_t n_added, TableForm form) {
  if (q < 1 || q > 21) fail(Status::invalid_argument, std::string(kWhat) + ": q must be 1..21");
  if (coarse.empty()) fail(Status::invalid_argument, std::string(kWhat) + ": the coarse level is empty");
  if (vq.codebook.empty()) fail(Status::invalid_argument, std::string(kWhat) + ": empty codebook");
  BitReader r(data, size, kWhat);
  const std::uint64_t step = r.exp_golomb();
  if (step > kMaxStep)
    fail(Status::bad_layer, std::string(kWhat) + ": residual step " + std::to_string(step) + " is above 2^21 - 1");
  const HuffmanCode gap_code = HuffmanCode::read(r, kAlphabet, std::string(kWhat) + " anchor table", form);
  const HuffmanCode index_code =
      HuffmanCode::read(r, static_cast<std::uint32_t>(vq.codebook.size()), std::string(kWhat) + " index table", form);
  std::array<HuffmanCode, 3> res_code;
  if (step > 0)
    for (std::size_t a = 0; a < 3; ++a)
      res_code[a] = HuffmanCode::read(r, kAlphabet, std::string(kWhat) + " residual table " + std::to_string(a), form);
  const auto s = static_cast<std::int64_t>(step);
  std::vector<GridPoint> points;
  std::uint64_t anchor = 0;
  for (std::uint64_t j = 0; j < n_added; ++j) {
    anchor += get_escaped(r, gap_code);
    if (anchor >= coarse.size())
      fail(Status::bad_layer, std::string(kWhat) + ": anchor " + std::to_string(anchor) + " of point " +
                                  std::to_string(j) + " is beyond the " + std::to_string(coarse.size()) + " coarse points");
    const auto& code = vq.codebook[index_code.decode(r)];
    const GridPoint& a = coarse[static_cast<std::size_t>(anchor)];
    GridPoint p{};
    for (std::size_t c = 0; c < 3; ++c) {
      // |a| < 2^21, |code| < 2^21, |s * residual| < 2^53: no overflow.
      std::int64_t v = std::int64_t{a[c]} + code[c];
      if (s > 0) v += s * unzigzag(get_escaped(r, res_code[c]));
      p[c] = static_cast<std::uint32_t>(clamp_grid(v, q));
    }
    // Bounded by n_added, which the header's limits bound.
    points.push_back(p);
  }
  r.expect_end();
  sort_canonical(points);
  for (std::size_t j = 1; j < points.size(); ++j)
    if (points[j] == points[j - 1])
      fail(Status::bad_layer, std::string(kWhat) + ": two added points coincide");
  std::size_t i = 0;
  for (const GridPoint& p : points) {
    while (i < coarse.size() && coarse[i] < p) ++i;
    if (i < coarse.size() && coarse[i] == p)
      fail(Status::bad_layer, std::string(kWhat) + ": an added point coincides with a coarse point");
  }
  return points;
}

VectorQuantizer train_layer_codebook(const std::vector<VqTrainingLayer>& layers, int bits, int anchors) {
  if (bits < 0 || bits > 16) fail(Status::invalid_argument, "vector quantizer: bits must be 0..16");
  struct Sample {
    IPoint p;
    std::size_t layer;
  };
  std::vector<Sample> samples;
  std::vector<std::vector<IPoint>> coarse(layers.size());
  std::vector<KdTree<std::int64_t>> trees(layers.size());
  std::vector<VqVector> data;
  for (std::size_t l = 0; l < layers.size(); ++l) {
    for (const GridPoint& c : canonical_copy(*layers[l].coarse)) coarse[l].push_back(to_ipoint(c));
    if (coarse[l].empty()) continue;
    trees[l] = KdTree<std::int64_t>(coarse[l]);
    for (const GridPoint& a : canonical_copy(*layers[l].added)) {
      const IPoint p = to_ipoint(a);
      const IPoint& c = coarse[l][trees[l].nearest(p).index];
      samples.push_back({p, l});
      data.push_back({double(p[0] - c[0]), double(p[1] - c[1]), double(p[2] - c[2])});
    }
  }
  if (data.empty()) fail(Status::invalid_argument, "vector quantizer: no refinement points to train on");
  std::vector<VqVector> cb = train_lbg(data, std::size_t{1} << bits);

  // Lloyd iterations on the encoder's own choice: each point takes the best
  // anchor among its nearest coarse points with that anchor's nearest codeword.
  const int m = std::clamp(anchors, 1, kMaxAnchors);
  const LloydRule rule;
  double previous = -1;
  for (int it = 0; it < rule.max_iterations; ++it) {
    const KdTree<double> tree = codebook_tree(cb);
    std::vector<VqVector> sum(cb.size(), VqVector{0, 0, 0});
    std::vector<std::size_t> count(cb.size(), 0);
    double total = 0;
    for (const Sample& s : samples) {
      KdTree<std::int64_t>::Hit hits[kMaxAnchors];
      const int n = trees[s.layer].nearest(s.p, m, hits);
      double best = -1;
      std::uint32_t best_code = 0;
      VqVector best_d{};
      for (int h = 0; h < n; ++h) {
        const IPoint& a = coarse[s.layer][hits[h].index];
        const VqVector d{double(s.p[0] - a[0]), double(s.p[1] - a[1]), double(s.p[2] - a[2])};
        const auto hit = tree.nearest(d);
        if (best < 0 || hit.d2 < best) best = hit.d2, best_code = hit.index, best_d = d;
      }
      total += best;
      for (std::size_t c = 0; c < 3; ++c) sum[best_code][c] += best_d[c];
      ++count[best_code];
    }
    const double mse = total / static_cast<double>(samples.size());
    if (mse == 0 || (previous >= 0 && previous - mse < rule.tolerance * previous)) break;
    previous = mse;
    for (std::size_t j = 0; j < cb.size(); ++j)
      if (count[j])
        for (std::size_t c = 0; c < 3; ++c) cb[j][c] = sum[j][c] / static_cast<double>(count[j]);
  }
  return round_codebook(cb);
}

}  // namespace hmc::detail
