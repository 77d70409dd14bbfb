#include "replay.hpp"

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "snapnav/glue/log_reader.hpp"
#include "snapnav/glue/log_writer.hpp"
#include "snapnav/glue/suggest.hpp"
#include "snapnav/glue/time.hpp"

namespace snapnav::replay {
namespace {

namespace fs = std::filesystem;

struct Built {
  std::string name;
  std::unique_ptr<ReplayNode> node;
};

std::string JoinNames() {
  std::string names;
  for (const auto& e : ReplayRegistry()) names += (names.empty() ? "" : ", ") + e.name;
  return names;
}

const NodeEntry* FindEntry(const std::string& name) {
  for (const auto& e : ReplayRegistry()) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

// " (did you mean 'X'?)" among the registered processes.
std::string NearestProcess(const std::string& name) {
  std::vector<std::string> names;
  for (const auto& e : ReplayRegistry()) names.push_back(e.name);
  return glue::DidYouMean(name, names);
}

}  // namespace

ConfigOverride ParseOverride(const std::string& text) {
  const auto colon = text.find(':');
  const auto eq = text.find('=');
  const auto dot = colon == std::string::npos ? std::string::npos : text.find('.', colon);
  if (colon == std::string::npos || dot == std::string::npos || eq == std::string::npos || !(colon < dot && dot < eq) ||
      colon == 0 || dot == colon + 1 || eq == dot + 1) {
    throw std::invalid_argument("--set '" + text + "': expected PROCESS:SECTION.KEY=VALUE, e.g. homing:homing.home=first");
  }
  return {text.substr(0, colon), text.substr(colon + 1, dot - colon - 1), text.substr(dot + 1, eq - dot - 1),
          text.substr(eq + 1)};
}

ReplayResult RunReplay(const ReplayOptions& options, std::ostream& log) {
  ReplayResult result;

  // Which processes, and the overrides of each (checked before anything runs).
  std::vector<const NodeEntry*> selected;
  for (const auto& name : options.only) {
    const NodeEntry* e = FindEntry(name);
    if (!e) {
      throw std::runtime_error("--only: no process '" + name + "'" + NearestProcess(name) +
                               " (replay runs: " + JoinNames() + ")");
    }
    if (std::find(selected.begin(), selected.end(), e) == selected.end()) selected.push_back(e);
  }
  const bool explicit_selection = !selected.empty();
  if (!explicit_selection) {
    for (const auto& e : ReplayRegistry()) selected.push_back(&e);
  }
  // Registry order, whatever the order of --only: the subscription order is part of the result.
  std::sort(selected.begin(), selected.end());
  std::map<std::string, std::vector<ConfigOverride>> overrides;
  for (const auto& text : options.sets) {
    ConfigOverride o = ParseOverride(text);
    if (!FindEntry(o.process)) {
      throw std::runtime_error("--set '" + text + "': no process '" + o.process + "'" + NearestProcess(o.process) +
                               " (replay runs: " + JoinNames() + ")");
    }
    if (std::find_if(selected.begin(), selected.end(), [&](const NodeEntry* e) { return e->name == o.process; }) ==
        selected.end()) {
      throw std::runtime_error("--set '" + text + "': process '" + o.process + "' is not selected by --only");
    }
    overrides[o.process].push_back(std::move(o));
  }
  // Every override applied to its process's config file now, before anything runs: a section or
  // key the file lacks is an error whether or not the process was named by --only.
  std::map<std::string, glue::IniFile> configs;
  for (const NodeEntry* e : selected) {
    const auto o = overrides.find(e->name);
    if (o == overrides.end()) continue;
    const std::string path = (fs::path(options.config_dir) / e->config_file).string();
    glue::IniFile ini = glue::IniFile::Load(path);
    for (const auto& k : o->second)
      ini.Set(k.section, k.key, k.value, "--set " + k.process + ":" + k.section + "." + k.key);
    configs.emplace(e->name, std::move(ini));
  }

  glue::LogReader reader(options.input);  // throws naming the file
  glue::Bus bus("memq://");

  // The recorder is subscribed first, so it sees every message before any node does: the
  // first message after an input is published is that input, every other one an output.
  glue::LogWriter writer(options.output);
  // A failed write stops the replay (the bus would only count it).
  bool awaiting_input = false;
  int64_t event_time = 0;
  std::exception_ptr write_error;
  bus.SubscribeRaw(".*", [&](const void* data, size_t size) {
    const std::string& channel = bus.current().channel;
    const bool input = awaiting_input;
    awaiting_input = false;
    if (input && !options.with_inputs) return;
    try {
      writer.WriteRaw(channel, event_time, std::string(static_cast<const char*>(data), size));
    } catch (...) {
      if (!write_error) write_error = std::current_exception();
    }
    if (input) return;
    ++result.outputs;
    ++result.outputs_by_channel[channel];
  });

  // Build the nodes, in registry order.
  std::vector<Built> nodes;
  std::set<std::string> output_channels;
  for (const NodeEntry* e : selected) {
    const std::string path = (fs::path(options.config_dir) / e->config_file).string();
    try {
      const auto overridden = configs.find(e->name);
      const glue::IniFile ini = overridden != configs.end() ? overridden->second : glue::IniFile::Load(path);
      log << "replay: " << e->name << ": config " << path << "\n";
      std::ostringstream unprinted;
      NodeContext context{bus, ini, options.channel_prefix, log,
                          options.print_config ? log : static_cast<std::ostream&>(unprinted), {}};
      auto node = e->make(context);
      for (const auto& ch : context.outputs) output_channels.insert(ch);
      nodes.push_back({e->name, std::move(node)});
      result.nodes.push_back(e->name);
    } catch (const std::exception& ex) {
      // Asked for by name: an error. Picked by default: left out, said why (its overrides were
      // checked above).
      if (explicit_selection) throw std::runtime_error(e->name + ": " + ex.what());
      result.skipped.push_back(e->name + ": " + ex.what());
      log << "replay: warning: " << e->name << " not run: " << ex.what() << "\n";
    }
  }
  if (nodes.empty()) throw std::runtime_error("no process could be started (see the warnings above)");
  {
    std::string names, outs;
    for (const auto& n : nodes) names += (names.empty() ? "" : ", ") + n.name;
    for (const auto& ch : output_channels) outs += (outs.empty() ? "" : ", ") + ch;
    log << "replay: " << options.input << " (" << reader.file_size() << " bytes) through " << names << " -> "
        << options.output << "; regenerated channels (not fed from the log): " << outs << "\n";
  }

  // Lockstep: one event, then handle until the queue is empty.
  const int64_t start_us = glue::MonotonicUtime();
  int64_t last_progress_us = start_us;
  glue::LogEvent ev;
  while (reader.Next(&ev)) {
    ++result.input_events;
    if (output_channels.count(ev.channel)) {
      ++result.dropped;
      continue;
    }
    event_time = ev.timestamp_us;
    awaiting_input = true;
    bus.PublishRaw(ev.channel, ev.data.data(), ev.data.size());
    ++result.fed;
    int64_t handled = 0;
    while (bus.HandleOnce(0)) {
      if (++handled > options.max_messages_per_event) {
        throw std::runtime_error("event " + std::to_string(result.input_events) + " on " + ev.channel +
                                 " caused more than " + std::to_string(options.max_messages_per_event) +
                                 " messages: the nodes feed each other without end");
      }
    }
    if (write_error) std::rethrow_exception(write_error);
    if (awaiting_input) throw std::logic_error("replay: the input on " + ev.channel + " was not delivered");
    if (options.progress_interval_s > 0) {
      const int64_t now = glue::MonotonicUtime();
      if (now - last_progress_us >= static_cast<int64_t>(options.progress_interval_s * 1e6)) {
        last_progress_us = now;
        log << "replay: " << std::fixed << std::setprecision(0)
            << 100.0 * static_cast<double>(reader.position()) / static_cast<double>(std::max<uint64_t>(1, reader.file_size()))
            << std::defaultfloat << std::setprecision(6) << "% of the log, " << result.input_events << " events, "
            << result.outputs << " outputs, " << (now - start_us) / 1000000 << " s\n";
      }
    }
  }
  for (auto& n : nodes) n.node->Finish();
  writer.Close();
  result.written = writer.events();
  result.damaged_bytes = reader.damaged_bytes();
  result.damage_count = static_cast<int>(reader.damage().size());
  result.bus_errors = bus.total_errors();

  // What each node did, what the bus counted, what was wrong with the log.
  for (const auto& n : nodes) n.node->Report(log);
  bus.ReportStats(log);
  reader.ReportDamage(log, "replay: warning");
  log << "replay: " << result.input_events << " input events (" << result.fed << " fed, " << result.dropped
      << " on regenerated channels not fed), " << result.outputs << " outputs, " << result.written
      << " events written to " << options.output << " in " << std::fixed << std::setprecision(1)
      << (glue::MonotonicUtime() - start_us) * 1e-6 << std::defaultfloat << std::setprecision(6) << " s\n";
  return result;
}

}  // namespace snapnav::replay
