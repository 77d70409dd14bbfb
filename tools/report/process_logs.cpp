#include "process_logs.hpp"

#include <regex>

namespace snapnav::report {

bool ProcessLog::complete() const {
  for (const auto& r : runs) {
    if (!r.reported) return false;
  }
  return true;
}

std::map<std::string, ChannelCounts> ProcessLog::Totals() const {
  std::map<std::string, ChannelCounts> out;
  for (const auto& r : runs) {
    for (const auto& [ch, c] : r.channels) {
      ChannelCounts& t = out[ch];
      t.received += c.received;
      t.published += c.published;
      t.rejected += c.rejected;
      t.handler_errors += c.handler_errors;
    }
  }
  return out;
}

ProcessLog ParseProcessLog(const std::string& name, std::istream& in) {
  static const std::regex header(R"(^--- launch: (\S+) run (\d+), pid (\d+))");
  static const std::regex stats(R"(^  (\S+) +received (\d+), published (\d+), rejected (\d+), handler errors (\d+))");
  ProcessLog log;
  log.name = name;
  const std::string launcher_prefix = "launch: " + name + ": ";
  std::string line;
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_search(line, m, header)) {
      ProcessRun r;
      r.run = std::stoi(m[2]);
      r.pid = std::stoi(m[3]);
      log.runs.push_back(r);
      continue;
    }
    if (line.rfind(launcher_prefix, 0) == 0) {
      log.launcher_lines.push_back(line.substr(8));
      continue;
    }
    if (std::regex_search(line, m, stats)) {
      if (log.runs.empty()) log.runs.push_back(ProcessRun{1, 0, false, {}});
      ProcessRun& r = log.runs.back();
      r.reported = true;
      ChannelCounts& c = r.channels[m[1]];
      c.received = std::stoull(m[2]);
      c.published = std::stoull(m[3]);
      c.rejected = std::stoull(m[4]);
      c.handler_errors = std::stoull(m[5]);
    }
  }
  return log;
}

}  // namespace snapnav::report
