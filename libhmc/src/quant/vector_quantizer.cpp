// SPDX-License-Identifier: AGPL-3.0-or-later
#include "quant/vector_quantizer.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "util/error.hpp"

namespace hmc::detail {

namespace {

constexpr double kSplit = 0.2;
constexpr std::int32_t kMaxEntry = (std::int32_t{1} << 21) - 1;

struct Assignment {
  std::vector<std::uint32_t> cell;  // per vector
  std::vector<double> d2;           // per vector
  double total = 0;
};

Assignment assign(const std::vector<VqVector>& data, const std::vector<VqVector>& codebook) {
  const KdTree<double> tree(codebook);
  Assignment a;
  a.cell.resize(data.size());
  a.d2.resize(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto hit = tree.nearest(data[i]);
    a.cell[i] = hit.index;
    a.d2[i] = hit.d2;
    a.total += hit.d2;
  }
  return a;
}

// Lloyd iterations from `codebook`; returns the final mean squared error.
double lloyd(const std::vector<VqVector>& data, std::vector<VqVector>& codebook, const LloydRule& rule) {
  const auto n = static_cast<double>(data.size());
  double previous = -1;
  for (int it = 0;; ++it) {
    Assignment a = assign(data, codebook);
    const double mse = a.total / n;
    const bool converged = previous >= 0 && (previous - mse) < rule.tolerance * previous;
    if (mse == 0 || converged || it >= rule.max_iterations) return mse;
    previous = mse;
    std::vector<VqVector> sum(codebook.size(), VqVector{0, 0, 0});
    std::vector<std::size_t> count(codebook.size(), 0);
    for (std::size_t i = 0; i < data.size(); ++i) {
      for (std::size_t c = 0; c < 3; ++c) sum[a.cell[i]][c] += data[i][c];
      ++count[a.cell[i]];
    }
    for (std::size_t j = 0; j < codebook.size(); ++j) {
      if (count[j]) {
        for (std::size_t c = 0; c < 3; ++c) codebook[j][c] = sum[j][c] / static_cast<double>(count[j]);
        continue;
      }
      // An empty cell takes the worst-served vector, which then forms its own cell.
      std::size_t worst = 0;
      for (std::size_t i = 1; i < data.size(); ++i)
        if (a.d2[i] > a.d2[worst]) worst = i;
      codebook[j] = data[worst];
      a.d2[worst] = 0;
    }
  }
}

}  // namespace

std::vector<VqVector> train_lbg(const std::vector<VqVector>& data, std::size_t k, const LloydRule& rule) {
  if (data.empty() || k == 0) fail(Status::invalid_argument, "vector quantizer: no training data");
  // More codewords than distinct vectors would only repeat entries.
  std::vector<VqVector> distinct = data;
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  k = std::min(k, distinct.size());

  VqVector mean{0, 0, 0};
  for (const auto& v : data)
    for (std::size_t c = 0; c < 3; ++c) mean[c] += v[c];
  for (double& m : mean) m /= static_cast<double>(data.size());
  std::vector<VqVector> codebook{mean};
  while (codebook.size() < k) {
    const Assignment a = assign(data, codebook);
    const std::size_t size = codebook.size();
    std::vector<VqVector> sum(size, VqVector{0, 0, 0}), sum2(size, VqVector{0, 0, 0});
    std::vector<double> error(size, 0);
    std::vector<std::size_t> count(size, 0);
    for (std::size_t i = 0; i < data.size(); ++i) {
      const std::uint32_t j = a.cell[i];
      for (std::size_t c = 0; c < 3; ++c) {
        const double d = data[i][c] - codebook[j][c];
        sum[j][c] += d;
        sum2[j][c] += d * d;
      }
      error[j] += a.d2[i];
      ++count[j];
    }
    // Which cells split: all of them, or the worst ones when that overshoots k.
    std::vector<std::size_t> order(size);
    std::iota(order.begin(), order.end(), 0);
    const std::size_t splits = std::min(size, k - size);
    if (splits < size)
      std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return error[x] > error[y]; });
    order.resize(splits);
    std::sort(order.begin(), order.end());
    for (std::size_t j : order) {
      VqVector e{0, 0, 0};
      if (count[j]) {
        const auto n = static_cast<double>(count[j]);
        for (std::size_t c = 0; c < 3; ++c) {
          const double m = sum[j][c] / n;
          e[c] = kSplit * std::sqrt(std::max(0.0, sum2[j][c] / n - m * m));
        }
      }
      VqVector lo = codebook[j], hi = codebook[j];
      for (std::size_t c = 0; c < 3; ++c) lo[c] -= e[c], hi[c] += e[c];
      codebook[j] = lo;
      codebook.push_back(hi);
    }
    lloyd(data, codebook, rule);
  }
  if (codebook.size() == 1) lloyd(data, codebook, rule);
  return codebook;
}

double quantization_mse(const std::vector<VqVector>& data, const std::vector<VqVector>& codebook) {
  if (data.empty()) return 0;
  return assign(data, codebook).total / static_cast<double>(data.size());
}

VectorQuantizer round_codebook(const std::vector<VqVector>& codebook) {
  VectorQuantizer vq;
  vq.codebook.resize(codebook.size());
  for (std::size_t j = 0; j < codebook.size(); ++j)
    for (std::size_t c = 0; c < 3; ++c) {
      const double v = std::clamp(std::round(codebook[j][c]), -double(kMaxEntry), double(kMaxEntry));
      vq.codebook[j][c] = static_cast<std::int32_t>(v);
    }
  return vq;
}

KdTree<double> codebook_tree(const std::vector<VqVector>& codebook) { return KdTree<double>(codebook); }

}  // namespace hmc::detail
