// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Independent work items on a few threads, with results that do not depend on the number of
// threads: item i is computed by one call fn(i) that writes only what belongs to i (which thread
// runs it does not matter).

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

namespace lidarcal {

/// The threads to use when `requested` is 0 (automatic): the machine's cores, at most `cap`.
inline int threadsFor(int requested, int cap = 8) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return std::clamp(static_cast<int>(hw == 0 ? 1u : hw), 1, cap);
}

/// fn(i) for every i in [0, n), on up to `threads` threads (the calling one among them), each
/// taking the next index not yet taken. If calls throw, the exception of the smallest such i is
/// rethrown after every thread stopped: the one a serial loop would have met first (indices are
/// taken in increasing order and every index taken is run, so every index below the smallest
/// failing one ran, and a thread stops only at a failure of its own).
template <class Fn>
void parallelFor(std::size_t n, int threads, Fn&& fn) {
  const std::size_t t_count =
      std::min<std::size_t>(n, static_cast<std::size_t>(std::max(threads, 1)));
  if (t_count <= 1) {
    for (std::size_t i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  std::vector<std::exception_ptr> error(t_count);
  std::vector<std::size_t> failed_at(t_count, n);
  auto work = [&](std::size_t t) {
    for (std::size_t i = next++; i < n; i = next++) {
      try {
        fn(i);
      } catch (...) {
        error[t] = std::current_exception();
        failed_at[t] = i;
        return;
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(t_count - 1);
  for (std::size_t t = 1; t < t_count; ++t) pool.emplace_back(work, t);
  work(0);
  for (auto& th : pool) th.join();
  const auto first = static_cast<std::size_t>(std::min_element(failed_at.begin(), failed_at.end()) -
                                              failed_at.begin());
  if (error[first]) std::rethrow_exception(error[first]);
}

}  // namespace lidarcal
