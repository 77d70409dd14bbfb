#pragma once
// Small text helpers for evaluation and benchmark reports (summary.json, report.md).
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

// s as a JSON string literal (quotes and backslashes escaped; paths may hold spaces).
inline std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace snapnav::eval
