#pragma once
// Small string tests shared by the tools and processes (file names by their endings).

#include <string>

namespace snapnav::glue {

// Whether `s` ends with `suffix` ("map.gridmap.gz" ends with ".gz" and ".gridmap.gz").
inline bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace snapnav::glue
