// Minimal parallel-for over independent jobs (a pool of threads kept between calls, dynamic
// scheduling).
#pragma once

#include <algorithm>
#include <atomic>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace osteon::detail {

/// Number of workers to use for `jobs` jobs when `requested` threads were asked for (0 = all
/// cores).
inline int worker_count(int requested, long jobs) {
  int hw = static_cast<int>(std::thread::hardware_concurrency());
  int n = requested > 0 ? requested : std::max(1, hw);
  return static_cast<int>(std::max(1L, std::min<long>(n, jobs)));
}

/// Vertices per job of a light pass over the vertices (a box, a maximum; ~20 instructions per
/// vertex): below this a second worker may cost more than it saves, since on a busy machine
/// (other programs, Blender's own threads) the spawned thread can wait a scheduler slice
/// (milliseconds) before it runs, and the pass waits for it. (On the loaded 2-core VM, cow x4
/// with such passes split at 16k-32k vertices timed 8-18 % slower than without in two A/B runs,
/// within that machine's noise: the threshold is a precaution, not a measured optimum.)
inline constexpr long kVerticesPerPass = 131072;

/// Runs body(w) for w = 1 .. workers - 1 on threads kept from call to call and body(0) on the
/// calling thread, and returns when all are done; `body` must not throw. False (nothing run)
/// when the pool is in use (a nested parallel_for, or another thread's): the caller then starts
/// threads of its own. (worker_pool.cpp)
bool pool_run(int workers, const std::function<void(int)>& body);

/// Calls fn(job, worker) for job in [0, jobs) on up to `threads` workers; rethrows the first error.
template <class Fn>
void parallel_for(long jobs, int threads, Fn&& fn) {
  const int workers = worker_count(threads, jobs);
  if (workers <= 1) {
    for (long j = 0; j < jobs; ++j) fn(j, 0);
    return;
  }
  std::atomic<long> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto body = [&](int worker) {
    try {
      for (long j = next++; j < jobs; j = next++) fn(j, worker);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = jobs;
    }
  };
  if (!pool_run(workers, body)) {
    std::vector<std::thread> threads;
    for (int w = 1; w < workers; ++w) threads.emplace_back(body, w);
    body(0);
    for (auto& t : threads) t.join();
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace osteon::detail
