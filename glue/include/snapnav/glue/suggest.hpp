#pragma once
// "Did you mean ...?" for a mistyped name: a config key, a section, a flag, a process.

#include <string>
#include <vector>

namespace snapnav::glue {

// Edit distance between `a` and `b`: insertions, deletions, substitutions and transpositions of
// two neighbouring characters each count 1 (optimal string alignment).
int EditDistance(const std::string& a, const std::string& b);

// The name of `known` nearest to `name` when it is near enough to be what was meant (at most a
// third of the longer name's characters differ, at most 3 edits: "x" suggests nothing, "ttl" "tll"),
// else "". Ties go to the first in `known`; `name` itself never is a suggestion.
std::string NearestName(const std::string& name, const std::vector<std::string>& known);

// " (did you mean 'X'?)" for NearestName's answer, "" when there is none.
std::string DidYouMean(const std::string& name, const std::vector<std::string>& known,
                       const std::string& quote_open = "'", const std::string& quote_close = "'");

}  // namespace snapnav::glue
