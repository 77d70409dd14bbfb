// launch: runs a deployment file (config/deploy/*.deploy): the processes for this host, supervised.
#include <unistd.h>

#include <ctime>
#include <filesystem>
#include <iostream>

#include "deployment.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/lcm_url.hpp"
#include "supervisor.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;

std::string ThisHost() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "localhost";
  return name;
}

std::string OwnFolder() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : self.parent_path().string();
}

std::string UtcStamp() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", &tm);
  return buf;
}

int Main(int argc, char** argv) {
  std::string host = ThisHost(), groups, out, bin = OwnFolder(), lcm_url, status_file;
  double status_every_s = 10, duration_s = 0;
  bool check = false;
  glue::Flags flags(
      "launch DEPLOYMENT [NAME=VALUE...]",
      "Runs the processes of a deployment file (config/deploy/*.deploy) whose host is this machine, in file\n"
      "order: prefixes each line of their output with the process name, restarts them by their restart\n"
      "policy, reports their states (every --status-every-s, on SIGUSR1, at the end), and on Ctrl-C or\n"
      "SIGTERM stops them in reverse order (stop signal, grace time, then SIGKILL). Exits non-zero if a\n"
      "required process failed. NAME=VALUE sets a variable of the file's [variables]. Processes for other\n"
      "hosts are started by a launcher on that host with the same file (--host).");
  flags.AddString("host", &host, "this machine's name in the file's host keys (* and localhost match any)",
                  "this machine's hostname");
  flags.AddString("group", &groups, "only the processes of these groups (comma-separated; default: all)");
  flags.AddString("out", &out, "${out}: the run's output folder (default: logs/<deployment>-<UTC time>)");
  flags.AddString("bin", &bin, "${bin}: folder of the snapnav binaries", "the launcher's own folder");
  flags.AddString("lcm-url", &lcm_url, "${lcm_url} and every process's LCM_DEFAULT_URL (default: $LCM_DEFAULT_URL or the host-local bus)");
  flags.AddDouble("status-every-s", &status_every_s, "print every process's state this often; 0: on SIGUSR1 and at the end only");
  flags.AddString("status-file", &status_file, "rewrite this file on every change: name, state, pid, runs, restarts, last exit (tab-separated)");
  flags.AddDouble("duration-s", &duration_s, "stop the deployment after this long; 0: when it ends, or on Ctrl-C");
  flags.AddBool("check", &check, "read the file, check every program is installed, print the plan and exit");
  flags.AllowPositional("DEPLOYMENT [NAME=VALUE...]", "the deployment file, then variables of its [variables]");
  if (!flags.Parse(argc, argv)) return 0;
  if (flags.positional().empty()) throw glue::FlagError("expected a DEPLOYMENT file (see --help)");
  if (status_every_s < 0 || duration_s < 0) throw glue::FlagError("--status-every-s and --duration-s must be >= 0");

  const std::string path = flags.positional()[0];
  launch::LoadOptions load;
  for (size_t i = 1; i < flags.positional().size(); ++i) {
    const std::string& a = flags.positional()[i];
    const auto eq = a.find('=');
    if (eq == std::string::npos || eq == 0) throw glue::FlagError("expected NAME=VALUE after the deployment file, got '" + a + "'");
    load.overrides[a.substr(0, eq)] = a.substr(eq + 1);
  }
  if (lcm_url.empty()) lcm_url = glue::DefaultLcmUrl();
  const fs::path config_dir = SNAPNAV_CONFIG_DIR;
  // ${out} needs the deployment's name: read the file once to learn it.
  load.builtins = {{"bin", bin},   {"config", config_dir.string()}, {"root", config_dir.parent_path().string()},
                   {"out", out}, {"lcm_url", lcm_url},            {"host", host}};
  if (out.empty()) {
    const auto first = launch::LoadDeployment(path, load);
    out = (config_dir.parent_path() / "logs" / (first.name + "-" + UtcStamp())).string();
    load.builtins["out"] = out;
  }
  const auto deployment = launch::LoadDeployment(path, load);

  std::vector<std::string> selected_groups = glue::SplitList(groups);
  std::set<std::string> known_groups;
  for (const auto& p : deployment.processes) known_groups.insert(p.group);
  for (const auto& g : selected_groups) {
    if (!known_groups.count(g)) {
      std::string names;
      for (const auto& k : known_groups) names += (names.empty() ? "" : ", ") + k;
      throw glue::FlagError("--group " + g + ": no such group in " + path + " (groups: " + names + ")");
    }
  }
  std::vector<launch::ProcessSpec> here;
  std::cerr << "launch: deployment '" << deployment.name << "' (" << path << "): " << deployment.description << "\n"
            << "launch: host " << host << (selected_groups.empty() ? ", every group" : ", groups " + groups)
            << ", bus " << lcm_url << (deployment.used_builtins.count("out") ? ", out " + out : "") << "\n";
  for (const auto& [k, v] : deployment.variables) std::cerr << "launch: variable " << k << " = " << v << "\n";
  int n = 0;
  for (const auto& p : deployment.processes) {
    const bool host_ok = launch::HostMatches(p.host, host);
    const bool group_ok =
        selected_groups.empty() || std::find(selected_groups.begin(), selected_groups.end(), p.group) != selected_groups.end();
    std::string why;
    if (!host_ok) why = "host " + p.host;
    if (!group_ok) why += std::string(why.empty() ? "" : ", ") + "group " + p.group;
    std::cerr << "launch: " << (why.empty() ? std::to_string(++n) + "." : "-") << " " << p.name << " [" << p.group
              << (p.host == "*" ? "" : " @" + p.host) << "] ";
    if (!why.empty()) {
      std::cerr << "not here (" << why << ")\n";
      continue;
    }
    std::cerr << p.CommandLine() << "\n           restart " << launch::RestartPolicyName(p.restart);
    if (p.restart != launch::RestartPolicy::kNever) std::cerr << " (limit " << p.restart_limit << ", back-off " << p.restart_delay_s << " s)";
    std::cerr << ", stop " << launch::SignalName(p.stop_signal) << " then SIGKILL after " << p.stop_grace_s << " s, ready "
              << launch::ReadyKindName(p.ready);
    if (p.ready == launch::ReadyKind::kDelay) std::cerr << " " << p.ready_delay_s << " s";
    if (!p.ready_pattern.empty()) std::cerr << " " << p.ready_pattern;
    std::cerr << (p.required ? ", required" : "") << (p.exit_stops_all ? ", its end stops all" : "")
              << (p.log_file.empty() ? "" : ", log " + p.log_file) << "\n";
    here.push_back(p);
  }
  if (here.empty()) {
    std::cerr << "launch: no process of " << path << " runs on host '" << host << "'"
              << (selected_groups.empty() ? "" : " in groups " + groups) << "\n";
    return check ? 0 : 1;
  }
  if (check) {
    int missing = 0;
    for (const auto& p : here) {
      if (launch::FindProgram(p.argv[0])) continue;
      const bool skip = p.if_missing == launch::IfMissing::kSkip;
      std::cerr << "launch: " << (skip ? "" : "error: ") << p.name << ": program '" << p.argv[0] << "' not found"
                << (skip ? " (if_missing = skip: it will be skipped)" : "") << "\n";
      if (!skip) ++missing;
    }
    std::cerr << "launch: check " << (missing ? "FAILED" : "passed") << ": " << here.size() << " processes for this host\n";
    return missing ? 1 : 0;
  }
  if (deployment.used_builtins.count("out")) fs::create_directories(out);

  launch::SupervisorOptions options;
  options.status_every_s = status_every_s;
  options.stop_after_s = duration_s;
  options.status_file = status_file;
  options.lcm_url = lcm_url;
  launch::InstallSignalHandlers();
  launch::Supervisor supervisor(std::move(here), options, std::cout, std::cerr);
  return supervisor.Run();
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
