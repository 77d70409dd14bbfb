#pragma once
// The one writer (and reader) of the JSON results of the tools: summary.json, bench.json,
// localize.json ... Keys keep the order they were set in (nlohmann::ordered_json), NaN and
// infinities are written as null, files are pretty-printed with a 2-space indent.
#include <string>
#include <type_traits>

#include <nlohmann/json.hpp>

namespace snapnav::results {

using Json = nlohmann::ordered_json;

// v, or null when it is NaN or infinite.
Json Number(double v);
// v rounded to `digits` after the point (the value a report prints with that many digits), or
// null when it is NaN or infinite.
Json Rounded(double v, int digits);
// As std::fixed << std::setprecision(digits) prints v: an integer as it is, a floating-point value
// rounded.
template <typename T>
Json Rounded(T v, int digits) {
  static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, "Rounded takes a number");
  if constexpr (std::is_integral_v<T>) {
    return v;
  } else {
    return Rounded(static_cast<double>(v), digits);
  }
}

// v with `digits` significant digits (as std::setprecision(digits) << v prints it: an integer when
// it prints without a point), or null when it is NaN or infinite.
Json Significant(double v, int digits = 6);

// Writes `j` to `path` (2-space indent, a trailing newline). Throws std::runtime_error naming the
// file when it cannot be written.
void WriteJsonFile(const std::string& path, const Json& j);
// The JSON in `path`. Throws std::runtime_error naming the file when it cannot be read, or the
// file and the byte position of a parse error.
Json ReadJsonFile(const std::string& path);

}  // namespace snapnav::results
