#pragma once
// Small text helpers for evaluation and benchmark reports (report.md; the JSON files are written
// with tools/results).
#include <iomanip>
#include <sstream>
#include <string>

namespace snapnav::eval {

// v with a fixed number of digits after the point.
inline std::string Fixed(double v, int digits = 2) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

}  // namespace snapnav::eval
