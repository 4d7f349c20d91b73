// SPDX-License-Identifier: AGPL-3.0-or-later
// A budget of helper threads shared by the parts of one encode() or
// decode() call (EncodeOptions::threads, DecodeOptions::threads): a part
// that has work to spare asks for a helper and, when none is free, does the
// work on its own thread. What is computed never depends on where: the
// parts split work whose pieces are independent and combine the results in
// a fixed order.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <future>
#include <system_error>
#include <utility>

namespace hmc::detail {

class HelperBudget {
 public:
  /// `threads` counts the caller's: threads - 1 helpers (none for 0 or 1).
  explicit HelperBudget(unsigned threads) : free_(static_cast<int>(std::min(threads, 64u)) - 1) {}
  HelperBudget(const HelperBudget&) = delete;
  HelperBudget& operator=(const HelperBudget&) = delete;

  /// Runs `job` on a new thread if a helper is free and returns the future
  /// of its result (its exception, if it throws); otherwise returns an
  /// invalid future and the caller does the work. The budget must outlive
  /// the job: wait for every future it returned.
  template <class Job>
  auto try_run(Job job) -> std::future<decltype(job())> {
#ifdef HMC_NO_THREADS
    // A platform without threads (WebAssembly without -pthread): every part
    // does its work on the caller's thread, which computes the same result.
    (void)job;
    return {};
#endif
    if (free_.fetch_sub(1) <= 0) {
      free_.fetch_add(1);
      return {};
    }
    try {
      return std::async(std::launch::async, [this, job = std::move(job)]() mutable {
        struct Release {
          std::atomic<int>& count;
          ~Release() { count.fetch_add(1); }
        } release{free_};
        return job();
      });
    } catch (const std::system_error&) {  // no thread to be had
      free_.fetch_add(1);
      return {};
    }
  }

 private:
  std::atomic<int> free_;
};

/// Calls f(begin, end) on the ranges [0, n / 2) here and [n / 2, n) on a
/// helper, when `helpers` has one free and n is at least `min_n`; else
/// f(0, n) here. The two calls must touch disjoint outputs. Rethrows an
/// exception of either, the first range's first, once both are done.
template <class F>
void split_range(HelperBudget* helpers, std::size_t n, std::size_t min_n, F&& f) {
  std::future<void> other;
  if (helpers && n >= min_n) other = helpers->try_run([&f, n] { f(n / 2, n); });
  if (!other.valid()) {
    f(std::size_t{0}, n);
    return;
  }
  try {
    f(std::size_t{0}, n / 2);
  } catch (...) {
    other.wait();
    throw;
  }
  other.get();
}

}  // namespace hmc::detail
