#pragma once
// Values of the evaluations' summary.json as their reports print them.
#include "results.hpp"

namespace snapnav::eval {

// 4 digits after the point (NaN as null, as results::Rounded).
template <typename T>
results::Json R4(T v) {
  return results::Rounded(v, 4);
}

}  // namespace snapnav::eval
