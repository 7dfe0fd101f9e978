// Parallel loops over index ranges with std::thread.
//
// std::thread rather than OpenMP: libgomp hangs a child process forked after the
// parent used it, and Python forks (multiprocessing's default start method).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace lf3pm {

/// Number of worker threads to use: `requested`, or all hardware threads when 0.
inline int resolve_threads(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

/// Calls body(begin, end) on disjoint chunks of [0, n) from `threads` threads.
/// Chunks are handed out dynamically (uneven work per index is common: rays that
/// hit near vs. far). The first exception thrown by a body is rethrown here.
template <typename Body>
void parallel_for(std::size_t n, std::size_t chunk, int threads, Body&& body) {
  if (n == 0) return;
  chunk = std::max<std::size_t>(chunk, 1);
  const int workers = static_cast<int>(std::min<std::size_t>(resolve_threads(threads), (n + chunk - 1) / chunk));
  if (workers <= 1) {
    for (std::size_t b = 0; b < n; b += chunk) body(b, std::min(n, b + chunk));
    return;
  }
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&]() {
    try {
      for (;;) {
        const std::size_t b = next.fetch_add(chunk);
        if (b >= n) return;
        body(b, std::min(n, b + chunk));
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next.store(n);
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (int i = 1; i < workers; ++i) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace lf3pm
