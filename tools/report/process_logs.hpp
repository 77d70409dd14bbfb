#pragma once
// The log files the launcher writes for each process (log_file = ...): every line of the
// process's output, one "--- launch: NAME run K, pid P: COMMAND" header per run, and the
// launcher's messages about it ("launch: NAME: ..."). snapnav processes end each run with
// their bus counts, one line per channel (glue::Bus::ReportStats):
//   "  CHANNEL   received N, published N, rejected N, handler errors N[ (last: ...)]"
// A run killed by a signal prints none: its counts are unknown.

#include <cstdint>
#include <istream>
#include <map>
#include <string>
#include <vector>

namespace snapnav::report {

struct ChannelCounts {
  uint64_t received = 0;
  uint64_t published = 0;
  uint64_t rejected = 0;
  uint64_t handler_errors = 0;
};

struct ProcessRun {
  int run = 0;    // 1, 2, ... (from the header; 1 without one)
  int pid = 0;    // 0: no header
  bool reported = false;  // it printed its bus counts
  std::map<std::string, ChannelCounts> channels;
};

struct ProcessLog {
  std::string name;
  std::vector<ProcessRun> runs;
  std::vector<std::string> launcher_lines;  // "launch: NAME: ..." lines, without the "launch: " prefix
  bool complete() const;                    // every run reported its counts
  // Sums over the runs that reported.
  std::map<std::string, ChannelCounts> Totals() const;
};

ProcessLog ParseProcessLog(const std::string& name, std::istream& in);

}  // namespace snapnav::report
