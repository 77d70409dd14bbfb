#pragma once
// The skeleton of every bus process's main, written once: say which config file was read and print
// the effective config, install the SIGINT/SIGTERM handlers, open the bus, build the node on it, say
// what it reads and publishes, run the bus until a signal (or the end of a file:// log), then the
// node's report and the bus's counts (received, malformed, handler errors per channel).
//
//   return glue::RunNode<processes::HomingNode>("homing", common.config, config, common.lcm_url,
//       [&](const processes::HomingNode& node, const glue::Bus& bus) { return "frames from ..."; });
//
// The node is built as Node(bus, config, extra...). It must have Report(std::ostream&); a node with
// Finish() (a memory to save, say) has it called after the bus stops, also when the bus throws, so
// nothing is lost.

#include <iostream>
#include <string>
#include <type_traits>
#include <utility>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/shutdown.hpp"

namespace snapnav::glue {

namespace run_node_detail {
template <class T, class = void>
struct HasFinish : std::false_type {};
template <class T>
struct HasFinish<T, std::void_t<decltype(std::declval<T&>().Finish())>> : std::true_type {};
}  // namespace run_node_detail

// "NAME: config PATH" and the config's own Print, as every process starts.
template <class Config>
void PrintConfig(const std::string& name, const std::string& config_path, const Config& config, std::ostream& out) {
  out << name << ": config " << config_path << "\n";
  config.Print(out);
}

// `describe(node, bus)` returns the line said once the node is built (without "NAME: " and the
// newline; empty: nothing said). Returns main's exit status (0).
template <class Node, class Config, class Describe, class... Extra>
int RunNode(const std::string& name, const std::string& config_path, const Config& config, const std::string& lcm_url,
            Describe&& describe, Extra&&... extra) {
  PrintConfig(name, config_path, config, std::cerr);
  InstallShutdownHandlers();
  Bus bus(lcm_url);
  Node node(bus, config, std::forward<Extra>(extra)...);
  const std::string line = describe(static_cast<const Node&>(node), static_cast<const Bus&>(bus));
  if (!line.empty()) std::cerr << name << ": " << line << "\n";
  if constexpr (run_node_detail::HasFinish<Node>::value) {
    try {
      bus.Run();
    } catch (...) {
      node.Finish();
      throw;
    }
    node.Finish();
  } else {
    bus.Run();
  }
  node.Report(std::cerr);
  bus.ReportStats(std::cerr);
  return 0;
}

}  // namespace snapnav::glue
