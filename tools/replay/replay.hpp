#pragma once
// Deterministic replay: a recorded LCM log fed through the processing processes' nodes in
// lockstep, their outputs recorded into a new log.
//
// The nodes are the very classes the process binaries run (processes/<name>/<name>_node.*), all
// on one in-process memq:// bus. Each log event is published in log order, then the bus is
// handled until its queue is empty before the next event, so chains (landmarks -> homing,
// placecells -> navigator) settle completely and in the same order on every run. Every message
// a node publishes is written to the output log, stamped with the event time of the input event
// that caused it. Messages the log holds on a channel that a replayed node publishes are not
// fed: the node makes them anew (they would otherwise arrive twice).
//
// Adding a process: one entry in ReplayRegistry() (replay_nodes.cpp).

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/ini.hpp"

namespace snapnav::replay {

// A process node held by replay.
class ReplayNode {
 public:
  virtual ~ReplayNode() = default;
  // The node's own counts (what the process prints when it stops).
  virtual void Report(std::ostream& out) const = 0;
  // At the end of the log (placecells writes its memory file).
  virtual void Finish() {}
};

// What a registry entry gets to build its node.
struct NodeContext {
  glue::Bus& bus;
  const glue::IniFile& ini;     // the process's config file, with --set overrides applied
  std::string channel_prefix;
  std::ostream& log;            // the node's progress lines (it keeps this stream)
  std::ostream& config_out;     // where the entry prints the effective configuration
  std::vector<std::string> outputs;  // the entry lists the channels its node publishes

  // Holds a node of type Node built from `args`; calls `report(node, out)` for Report() when
  // given, and `finish(node)` at the end of the log.
  template <class Node, class... Args>
  std::unique_ptr<ReplayNode> Hold(std::function<void(const Node&, std::ostream&)> report,
                                   std::function<void(Node&)> finish, Args&&... args);
};

struct NodeEntry {
  std::string name;         // the process's binary name, as --only takes it
  std::string config_file;  // its INI file in the config folder
  std::function<std::unique_ptr<ReplayNode>(NodeContext&)> make;
};

// Every process replay can run, in the order they are built (and subscribed).
const std::vector<NodeEntry>& ReplayRegistry();

struct ReplayOptions {
  std::string input;                  // the recorded log
  std::string output;                 // the log to write
  std::string config_dir;             // one INI per process, as the processes take them
  std::vector<std::string> only;      // process names; empty: every registered process
  std::vector<std::string> sets;      // overrides "PROCESS:SECTION.KEY=VALUE"
  std::string channel_prefix;         // prepended to every channel of every node
  bool with_inputs = false;           // also write the input events that were fed
  bool print_config = false;          // print each node's effective configuration (--print-config)
  double progress_interval_s = 2;     // wall time between progress lines; 0: none
  int64_t max_messages_per_event = 100000;  // more means the nodes feed each other forever
};

struct ReplayResult {
  int64_t input_events = 0;     // intact events of the input log
  int64_t fed = 0;              // published to the nodes
  int64_t dropped = 0;          // on a replayed node's output channel: made anew instead
  int64_t outputs = 0;          // messages the nodes published (written)
  int64_t written = 0;          // events in the output log
  std::vector<std::string> nodes;    // processes run
  std::vector<std::string> skipped;  // processes not run, with the reason
  std::map<std::string, int64_t> outputs_by_channel;
  uint64_t damaged_bytes = 0;   // of the input log
  int damage_count = 0;
  uint64_t bus_errors = 0;      // decode and handler errors counted by the bus (bad messages)
};

// Runs the replay; progress, configuration and reports go to `log`. Throws std::runtime_error
// (or glue::ConfigError, glue::LogError) naming what is wrong: an unknown process, a bad
// override, a config error, a node that cannot start when it was asked for by --only.
ReplayResult RunReplay(const ReplayOptions& options, std::ostream& log);

// "homing:homing.home=first" -> (process, section, key, value); throws std::invalid_argument.
struct ConfigOverride {
  std::string process, section, key, value;
};
ConfigOverride ParseOverride(const std::string& text);

// --- implementation of NodeContext::Hold ---
template <class Node>
class HeldNode : public ReplayNode {
 public:
  template <class... Args>
  explicit HeldNode(std::function<void(const Node&, std::ostream&)> report, std::function<void(Node&)> finish,
                    Args&&... args)
      : node_(std::forward<Args>(args)...), report_(std::move(report)), finish_(std::move(finish)) {}
  void Report(std::ostream& out) const override {
    if (report_) report_(node_, out);
  }
  void Finish() override {
    if (finish_) finish_(node_);
  }

 private:
  Node node_;
  std::function<void(const Node&, std::ostream&)> report_;
  std::function<void(Node&)> finish_;
};

template <class Node, class... Args>
std::unique_ptr<ReplayNode> NodeContext::Hold(std::function<void(const Node&, std::ostream&)> report,
                                              std::function<void(Node&)> finish, Args&&... args) {
  return std::make_unique<HeldNode<Node>>(std::move(report), std::move(finish), std::forward<Args>(args)...);
}

}  // namespace snapnav::replay
