#pragma once
// Row-parallel loop for the CPU references: static blocks of rows over std::threads.
#include <algorithm>
#include <thread>
#include <vector>

namespace bokeh {

inline int default_cpu_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

template <class RowFn>
void parallel_rows(int height, int threads, RowFn&& row_fn) {
  threads = std::clamp(threads, 1, std::max(1, height));
  if (threads == 1) {
    for (int y = 0; y < height; ++y) row_fn(y);
    return;
  }
  std::vector<std::jthread> workers;
  for (int t = 0; t < threads; ++t)
    workers.emplace_back([&, t] {
      for (int y = t; y < height; y += threads) row_fn(y);  // interleaved rows balance uneven cost
    });
}

}  // namespace bokeh
