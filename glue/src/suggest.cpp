#include "snapnav/glue/suggest.hpp"

#include <algorithm>

namespace snapnav::glue {

int EditDistance(const std::string& a, const std::string& b) {
  const size_t n = a.size(), m = b.size();
  std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1));
  for (size_t i = 0; i <= n; ++i) d[i][0] = static_cast<int>(i);
  for (size_t j = 0; j <= m; ++j) d[0][j] = static_cast<int>(j);
  for (size_t i = 1; i <= n; ++i) {
    for (size_t j = 1; j <= m; ++j) {
      const int cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[n][m];
}

std::string NearestName(const std::string& name, const std::vector<std::string>& known) {
  std::string best;
  int best_distance = 0;
  for (const auto& k : known) {
    if (k == name || k.empty()) continue;
    const int limit = std::min(static_cast<int>(std::max(name.size(), k.size()) / 3), 3);
    const int d = EditDistance(name, k);
    if (d <= limit && (best.empty() || d < best_distance)) {
      best = k;
      best_distance = d;
    }
  }
  return best;
}

std::string DidYouMean(const std::string& name, const std::vector<std::string>& known, const std::string& quote_open,
                       const std::string& quote_close) {
  const std::string nearest = NearestName(name, known);
  return nearest.empty() ? "" : " (did you mean " + quote_open + nearest + quote_close + "?)";
}

}  // namespace snapnav::glue
