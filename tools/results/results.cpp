#include "results.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace snapnav::results {

Json Number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json Rounded(double v, int digits) {
  if (!std::isfinite(v)) return nullptr;
  std::ostringstream text;
  text << std::fixed << std::setprecision(digits) << v;
  return std::stod(text.str());
}

Json Significant(double v, int digits) {
  if (!std::isfinite(v)) return nullptr;
  std::ostringstream text;
  text << std::setprecision(digits) << v;
  const std::string s = text.str();
  // "60", not "60.0", as the stream printed it (counts kept in doubles stay integers).
  if (s.find_first_not_of("-0123456789") == std::string::npos) return std::stoll(s);
  return std::stod(s);
}

void WriteJsonFile(const std::string& path, const Json& j) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << j.dump(2) << "\n";
  f.close();
  if (!f) throw std::runtime_error("cannot write " + path);
}

Json ReadJsonFile(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot read " + path);
  std::ostringstream text;
  text << f.rdbuf();
  try {
    return Json::parse(text.str());
  } catch (const Json::parse_error& e) {
    // e.what() is "[json.exception.parse_error.101] parse error at line L, column C: ...".
    std::string what = e.what();
    const size_t bracket = what.find("] ");
    if (bracket != std::string::npos) what = what.substr(bracket + 2);
    throw std::runtime_error(path + ": not JSON at byte " + std::to_string(e.byte) + ": " + what);
  }
}

}  // namespace snapnav::results
