#pragma once
// Timing for the benchmarks: the median over `runs` of the mean time per call of `per_run`
// calls of fn(i), i counting calls across runs. Medians, because these machines are noisy.

#include <algorithm>
#include <chrono>
#include <vector>

namespace snapnav::bench {

template <class Fn>
double MedianSecondsPerCall(int runs, int per_run, Fn&& fn) {
  std::vector<double> seconds;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < per_run; ++i) fn(r * per_run + i);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / per_run);
  }
  std::sort(seconds.begin(), seconds.end());
  return seconds[seconds.size() / 2];
}

}  // namespace snapnav::bench
