#pragma once
// Small text helpers for evaluation and benchmark reports (summary.json, report.md).
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

namespace snapnav::eval {

// v with a fixed number of digits after the point.
inline std::string Fixed(double v, int digits = 2) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

// s as a JSON string literal (quotes and backslashes escaped; paths may hold spaces).
inline std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// v as the inside of a JSON array of numbers: "1.5, 2, 3".
inline std::string JsonNumbers(const std::vector<double>& v) {
  std::ostringstream s;
  for (size_t i = 0; i < v.size(); ++i) s << (i ? ", " : "") << v[i];
  return s.str();
}

}  // namespace snapnav::eval
