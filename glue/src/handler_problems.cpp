#include "snapnav/glue/handler_problems.hpp"

#include <iostream>

namespace snapnav::glue {

void HandlerProblems::Skip(const std::string& reason, const std::string& detail, bool malformed) {
  ++skipped_[reason];
  if (malformed) bus_.CountDecodeError(reason + ": " + detail);  // per channel; printed, rate-limited
}

void HandlerProblems::InternalError(const std::string& what) {
  last_internal_error_ = what;
  const int64_t n = ++internal_errors_;
  if (n <= 5 || n % 100 == 0) std::cerr << process_ << ": internal error #" << n << ": " << what << "\n";
}

int64_t HandlerProblems::skipped(const std::string& reason) const {
  const auto it = skipped_.find(reason);
  return it == skipped_.end() ? 0 : it->second;
}

int64_t HandlerProblems::skipped_total() const {
  int64_t n = 0;
  for (const auto& [_, k] : skipped_) n += k;
  return n;
}

void HandlerProblems::Report(std::ostream& out) const {
  for (const auto& [reason, n] : skipped_) out << process_ << ":   skipped (" << reason << "): " << n << "\n";
  if (!last_internal_error_.empty()) out << process_ << ":   last internal error: " << last_internal_error_ << "\n";
}

}  // namespace snapnav::glue
