#pragma once
// Statistics for evaluation and benchmark reports (the same median everywhere).
#include <algorithm>
#include <vector>

namespace snapnav::eval {

// The median (the mean of the two middle values of an even count); `if_empty` for no values
// (0 where a count of nothing reads as zero, NaN where a report marks it missing).
inline double Median(std::vector<double> v, double if_empty = 0) {
  if (v.empty()) return if_empty;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  if (v.size() % 2) return *mid;
  return 0.5 * (*mid + *std::max_element(v.begin(), mid));
}

// The mean; 0 for no values.
inline double Mean(const std::vector<double>& v) {
  double s = 0;
  for (const double x : v) s += x;
  return v.empty() ? 0 : s / static_cast<double>(v.size());
}

}  // namespace snapnav::eval
