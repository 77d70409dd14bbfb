#pragma once
// What a node's handlers could not use, counted the same way in every process: messages skipped
// by reason (a malformed one is also counted as rejected on its channel by the bus, which prints
// the first few and then every 100th), and internal errors (an exception out of a handler's work,
// e.g. a failed publish: counted and printed the same way, never propagated into LCM).
#include <cstdint>
#include <exception>
#include <map>
#include <ostream>
#include <string>
#include <utility>

#include "snapnav/glue/bus.hpp"

namespace snapnav::glue {

class HandlerProblems {
 public:
  // `process` names the process in the printed lines ("laser-slam").
  HandlerProblems(Bus& bus, std::string process) : bus_(bus), process_(std::move(process)) {}

  // Counts a skipped message; a malformed one (`malformed`) also as rejected on the bus.
  void Skip(const std::string& reason, const std::string& detail, bool malformed);
  // Counts and prints (rate-limited) an internal error.
  void InternalError(const std::string& what);
  // Runs `work`; an exception out of it is an internal error "what: message".
  template <class F>
  void Guard(const char* what, F&& work) {
    try {
      work();
    } catch (const std::exception& e) {
      InternalError(std::string(what) + ": " + e.what());
    }
  }

  const std::map<std::string, int64_t>& skipped() const { return skipped_; }
  int64_t skipped(const std::string& reason) const;
  int64_t skipped_total() const;
  int64_t internal_errors() const { return internal_errors_; }
  const std::string& last_internal_error() const { return last_internal_error_; }
  // "PROCESS:   skipped (REASON): N" per reason and the last internal error, one line each.
  void Report(std::ostream& out) const;

 private:
  Bus& bus_;
  std::string process_;
  std::map<std::string, int64_t> skipped_;
  int64_t internal_errors_ = 0;
  std::string last_internal_error_;
};

}  // namespace snapnav::glue
