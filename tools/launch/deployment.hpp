#pragma once
// Deployment files (config/deploy/*.deploy): the processes of a lab deployment, one
// `[process NAME]` section each, started in file order. The file is INI as glue::IniFile reads it:
//
//   [deployment]   name, description
//   [variables]    NAME = VALUE, used as ${NAME}; `launch FILE NAME=VALUE` overrides one
//   [defaults]     any process key below, for every process that does not set it
//   [process NAME] command = PROGRAM ARGS... (required here), and the process keys
//   [include NAME] file = OTHER.deploy (relative to this file), for_each = VAR in V1,V2,...
//                  (optional), processes = P1,P2,... (optional: only these), and VARIABLE = VALUE
//                  for the other file's [variables]: that file's (chosen) processes, here in its
//                  file order, named NAME.PROCESS (NAME1.PROCESS, NAME2.PROCESS
//                  ... with for_each: one copy per value, ${VAR} the value and ${index} 1, 2, ...
//                  in this section's keys, and VAR set in the other file, one of its [variables]).
//                  The other file keeps its own [defaults] and variables.
//
// Every process key comes from its section or from [defaults]; a key in neither, a key this
// launcher does not know, an unknown ${variable} and a bad value are errors naming the file
// and line. Built-in variables: ${bin} (the binaries), ${config} (config/), ${root} (the
// project), ${out} (the run's output folder), ${lcm_url} (the bus), ${host} (this host).
// `$$` is a literal `$`.

#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "snapnav/glue/ini.hpp"

namespace snapnav::launch {

using glue::ConfigError;

enum class RestartPolicy { kNever, kOnFailure, kAlways };
// What the launcher waits for before it starts the next process of the file.
enum class ReadyKind { kNone, kDelay, kLine, kFile, kExited };
enum class EchoMode { kAll, kNone, kMatch };
enum class IfMissing { kError, kSkip };

const char* RestartPolicyName(RestartPolicy p);
const char* ReadyKindName(ReadyKind k);

struct ProcessSpec {
  std::string name;
  std::string where;                 // "FILE:LINE" of the section header, for messages
  std::vector<std::string> argv;     // the command, split into words, variables substituted
  std::string host = "*";            // * or localhost: any host
  std::string group = "main";
  bool required = true;              // failing for good (after its restarts) stops the deployment
  IfMissing if_missing = IfMissing::kError;  // program not found: error, or skip the process
  RestartPolicy restart = RestartPolicy::kNever;
  int restart_limit = 0;             // restarts allowed over the whole run
  double restart_delay_s = 1;        // back-off before the first restart; doubles each time ...
  double restart_delay_max_s = 10;   // ... up to this
  int stop_signal = 2;               // SIGINT
  double stop_grace_s = 5;           // then SIGKILL
  ReadyKind ready = ReadyKind::kNone;
  double ready_delay_s = 0;          // kDelay
  std::string ready_pattern;         // kLine: regular expression on a line of its output; kFile: path
  double ready_timeout_s = 30;       // kLine, kFile, kExited: longest wait
  bool exit_stops_all = false;       // its end (without a restart) stops the deployment
  std::string log_file;              // every line of its output, unprefixed; empty: none
  EchoMode echo = EchoMode::kAll;    // what of its output the launcher prints, prefixed
  std::string echo_pattern;          // kMatch: regular expression

  std::string CommandLine() const;   // argv joined, quoted where needed
};

struct Deployment {
  std::string path;
  std::string name;
  std::string description;
  std::vector<ProcessSpec> processes;           // file order = start order
  std::map<std::string, std::string> variables;  // [variables] after overrides and substitution
  std::set<std::string> used_builtins;           // built-in variables the file refers to
};

struct LoadOptions {
  std::map<std::string, std::string> builtins;   // bin, config, root, out, lcm_url, host
  std::map<std::string, std::string> overrides;  // NAME=VALUE of the command line ([variables] only)
  std::string overrides_origin = "command line";  // where the overrides come from, for messages
  int include_depth = 0;                          // files including this one (at most kMaxIncludeDepth)
};
inline constexpr int kMaxIncludeDepth = 4;

// Throws ConfigError naming the file and line.
Deployment LoadDeployment(const std::string& path, const LoadOptions& options);
Deployment ParseDeployment(const std::string& text, const std::string& origin, const LoadOptions& options);

// Splits a command line into words: blanks separate, '...' and "..." quote, \ escapes the next
// character (outside single quotes). Throws std::invalid_argument on an unbalanced quote.
std::vector<std::string> SplitCommand(const std::string& text);

// Replaces ${NAME} by lookup(NAME) and $$ by $; throws std::invalid_argument naming an unknown
// variable (lookup returned nullopt) or an unterminated ${.
std::string Substitute(const std::string& text,
                       const std::function<std::optional<std::string>(const std::string&)>& lookup);

// `*` and `localhost` match every host; anything else must equal this host's name.
bool HostMatches(const std::string& process_host, const std::string& this_host);

// Signal by name (INT, SIGTERM, ...) and back; throws std::invalid_argument on an unknown name.
int ParseSignal(const std::string& name);
std::string SignalName(int signal);

// The full path of a program as execvp would find it (a name with a slash: itself if executable);
// nullopt if there is none.
std::optional<std::string> FindProgram(const std::string& program);

}  // namespace snapnav::launch
