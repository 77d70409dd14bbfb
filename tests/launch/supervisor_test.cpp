// The launcher's supervision: restart decisions and back-off, and the Supervisor running real
// child processes (sh): prefixed output, restarts, readiness, ordered stop with grace and SIGKILL.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "supervisor.hpp"

namespace snapnav::launch {
namespace {

namespace fs = std::filesystem;

ProcessSpec Sh(const std::string& name, const std::string& script) {
  ProcessSpec p;
  p.name = name;
  p.where = "test.deploy:1";
  p.argv = {"/bin/sh", "-c", script};
  p.restart_delay_s = 0.05;
  p.restart_delay_max_s = 0.2;
  p.stop_grace_s = 2;
  p.ready_timeout_s = 5;
  return p;
}

struct RunResult {
  int rc = -1;
  std::string out, err;
  double seconds = 0;
  std::vector<ProcessStatus> status;
};

RunResult RunAll(std::vector<ProcessSpec> specs, SupervisorOptions o = {},
           std::function<void(Supervisor&, double)> on_tick = nullptr) {
  o.status_every_s = 0;
  o.poll_ms = 10;
  std::ostringstream out, err;
  RunResult r;
  {
    Supervisor s(std::move(specs), o, out, err);
    s.on_tick = std::move(on_tick);
    const auto t0 = std::chrono::steady_clock::now();
    r.rc = s.Run();
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.status = s.Status();
  }
  r.out = out.str();
  r.err = err.str();
  return r;
}

const ProcessStatus& Find(const RunResult& r, const std::string& name) {
  for (const auto& p : r.status) {
    if (p.name == name) return p;
  }
  throw std::runtime_error("no " + name);
}

bool Alive(int pid) { return pid > 0 && ::kill(pid, 0) == 0; }

// Processes of process group `pgid` that still run: those /proc lists with that group and a state
// other than zombie (a killed process whose parent died stays a zombie until init reaps it, which
// on a busy machine can take seconds, and kill(-pgid, 0) still finds it).
int RunningInGroup(int pgid) {
  int running = 0;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "stat");
    std::string stat;
    if (!std::getline(in, stat)) continue;  // gone meanwhile
    // pid (comm) state ppid pgrp ...: comm may hold spaces, so parse after its closing ')'.
    const auto close = stat.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(stat.substr(close + 1));
    char state = 0;
    int ppid = 0, pgrp = 0;
    rest >> state >> ppid >> pgrp;
    if (pgrp == pgid && state != 'Z' && state != 'X') ++running;
  }
  return running;
}

fs::path TempDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("snapnav_launch_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(RestartPolicy, Decisions) {
  ProcessSpec p;
  p.restart_limit = 2;
  p.restart_delay_s = 1;
  p.restart_delay_max_s = 3;
  p.restart = RestartPolicy::kNever;
  EXPECT_FALSE(DecideRestart(p, ExitStatus::Killed(SIGKILL), 0).restart);
  p.restart = RestartPolicy::kOnFailure;
  EXPECT_FALSE(DecideRestart(p, ExitStatus::Exited(0), 0).restart);
  const auto d = DecideRestart(p, ExitStatus::Exited(3), 0);
  EXPECT_TRUE(d.restart);
  EXPECT_DOUBLE_EQ(d.delay_s, 1);
  EXPECT_EQ(d.why, "restart = on-failure, restart 1 of 2");
  EXPECT_TRUE(DecideRestart(p, ExitStatus::Killed(SIGSEGV), 1).restart);
  const auto limit = DecideRestart(p, ExitStatus::Killed(SIGSEGV), 2);
  EXPECT_FALSE(limit.restart);
  EXPECT_EQ(limit.why, "restart limit 2 reached");
  p.restart = RestartPolicy::kAlways;
  EXPECT_TRUE(DecideRestart(p, ExitStatus::Exited(0), 0).restart);
}

TEST(RestartPolicy, BackOffDoublesUpToTheMaximum) {
  ProcessSpec p;
  p.restart_delay_s = 0.5;
  p.restart_delay_max_s = 3;
  EXPECT_DOUBLE_EQ(RestartDelay(p, 0), 0.5);
  EXPECT_DOUBLE_EQ(RestartDelay(p, 1), 1.0);
  EXPECT_DOUBLE_EQ(RestartDelay(p, 2), 2.0);
  EXPECT_DOUBLE_EQ(RestartDelay(p, 3), 3.0);
  EXPECT_DOUBLE_EQ(RestartDelay(p, 1000), 3.0);
}

TEST(ExitStatusText, Describes) {
  EXPECT_EQ(Describe(ExitStatus::Exited(0)), "exit code 0");
  EXPECT_EQ(Describe(ExitStatus::Exited(3)), "exit code 3");
  EXPECT_EQ(Describe(ExitStatus::Killed(SIGKILL)), "killed by SIGKILL");
  EXPECT_TRUE(ExitStatus::Exited(0).success());
  EXPECT_FALSE(ExitStatus::Killed(SIGINT).success());
}

TEST(Supervisor, PrefixesOutputFiltersEchoAndKeepsEverythingInTheLog) {
  const fs::path dir = TempDir("output");
  ProcessSpec a = Sh("alpha", "echo one; echo two >&2; printf 'no newline'");
  a.log_file = (dir / "alpha.log").string();
  ProcessSpec b = Sh("b", "echo keep this; echo drop this; printf 'p1\\rp2\\r\\n'");
  b.echo = EchoMode::kMatch;
  b.echo_pattern = "^keep|^p";
  const RunResult r = RunAll({a, b});
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("alpha | one\n"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("alpha | two\n"), std::string::npos) << r.err;  // stderr stays stderr
  EXPECT_NE(r.out.find("alpha | no newline\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("b     | keep this\n"), std::string::npos) << r.out;  // padded to the longest name
  EXPECT_EQ(r.out.find("drop this"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("b     | p1\nb     | p2\n"), std::string::npos) << r.out;  // \r ends a line too
  EXPECT_EQ(Find(r, "alpha").state, State::kExited);
  std::ifstream log(a.log_file);
  std::stringstream ss;
  ss << log.rdbuf();
  EXPECT_NE(ss.str().find("--- launch: alpha run 1, pid "), std::string::npos) << ss.str();
  EXPECT_NE(ss.str().find("\none\n"), std::string::npos);
  EXPECT_NE(ss.str().find("\ntwo\n"), std::string::npos);
  EXPECT_NE(ss.str().find("launch: alpha: finished (exit code 0)"), std::string::npos) << ss.str();
  fs::remove_all(dir);
}

TEST(Supervisor, RestartsACrashingProcessUpToItsLimitThenAnOptionalOneFails) {
  ProcessSpec crash = Sh("crash", "exit 3");
  crash.restart = RestartPolicy::kOnFailure;
  crash.restart_limit = 2;
  crash.required = false;
  const RunResult r = RunAll({crash});
  EXPECT_EQ(r.rc, 0) << r.err;  // not required
  const auto& s = Find(r, "crash");
  EXPECT_EQ(s.state, State::kFailed);
  EXPECT_EQ(s.runs, 3);
  EXPECT_EQ(s.restarts, 2);
  EXPECT_EQ(s.last_exit, "exit code 3");
  EXPECT_NE(r.err.find("launch: crash: ended (exit code 3) after"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("restarting in 0.05 s (restart = on-failure, restart 1 of 2)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("restarting in 0.10 s (restart = on-failure, restart 2 of 2)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("launch: crash: FAILED (exit code 3)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("restart limit 2 reached"), std::string::npos) << r.err;
}

TEST(Supervisor, ARequiredFailureStopsTheOthersAndFailsTheRun) {
  ProcessSpec keep = Sh("keep", "trap 'exit 0' INT; while :; do sleep 0.05; done");
  ProcessSpec crash = Sh("crash", "sleep 0.2; exit 1");
  const RunResult r = RunAll({keep, crash});
  EXPECT_EQ(r.rc, 1);
  EXPECT_EQ(Find(r, "crash").state, State::kFailed);
  EXPECT_EQ(Find(r, "keep").state, State::kStopped);
  EXPECT_NE(r.err.find("stopping (required process crash failed)"), std::string::npos) << r.err;
  EXPECT_LT(r.seconds, 3);
}

TEST(Supervisor, KilledProcessIsRestartedAndTheOthersKeepRunning) {
  ProcessSpec a = Sh("a", "trap 'exit 0' INT; while :; do sleep 0.05; done");
  ProcessSpec victim = Sh("victim", "trap 'exit 0' INT; while :; do sleep 0.05; done");
  victim.restart = RestartPolicy::kOnFailure;
  victim.restart_limit = 3;
  ProcessSpec c = Sh("c", "trap 'exit 0' INT; while :; do sleep 0.05; done");
  int a_pid = 0, victim_pid = 0, c_pid = 0, killed = 0;
  SupervisorOptions o;
  const RunResult r = RunAll({a, victim, c}, o, [&](Supervisor& s, double t) {
    if (t > 0.3 && killed == 0) {
      a_pid = s.Status("a").pid;
      c_pid = s.Status("c").pid;
      victim_pid = s.Status("victim").pid;
      ASSERT_GT(victim_pid, 0);
      ::kill(victim_pid, SIGKILL);
      killed = 1;
    }
    if (killed == 1 && s.Status("victim").runs == 2 && s.Status("victim").state == State::kRunning) {
      EXPECT_NE(s.Status("victim").pid, victim_pid);
      EXPECT_EQ(s.Status("a").pid, a_pid);  // untouched
      EXPECT_EQ(s.Status("c").pid, c_pid);
      killed = 2;
      s.RequestStop("test done");
    }
    if (t > 5) s.RequestStop("test timeout");
  });
  EXPECT_EQ(killed, 2) << r.err;
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(Find(r, "victim").runs, 2);
  EXPECT_EQ(Find(r, "victim").restarts, 1);
  EXPECT_EQ(Find(r, "a").runs, 1);
  EXPECT_EQ(Find(r, "c").runs, 1);
  EXPECT_NE(r.err.find("launch: victim: ended (killed by SIGKILL)"), std::string::npos) << r.err;
  for (const auto& p : r.status) EXPECT_EQ(p.state, State::kStopped) << p.name;
}

TEST(Supervisor, StopsInReverseStartOrderAndKillsAfterTheGraceTime) {
  const fs::path dir = TempDir("order");
  const std::string order = (dir / "order").string();
  auto quitter = [&](const std::string& name) {
    return Sh(name, "trap 'echo " + name + " >> " + order + "; exit 0' INT; while :; do sleep 0.05; done");
  };
  // Notes the stop signal, then goes on: only SIGKILL ends it (with the sleep child of its group).
  ProcessSpec stubborn = Sh("stubborn", "trap 'echo stubborn >> " + order + "' INT; sleep 30 & while :; do sleep 0.05; done");
  stubborn.stop_grace_s = 0.5;
  stubborn.required = false;
  ProcessSpec first = quitter("first"), second = quitter("second");
  int pid_sleep_group = 0, running_before_stop = 0;
  const RunResult r = RunAll({first, second, stubborn}, {}, [&](Supervisor& s, double t) {
    pid_sleep_group = s.Status("stubborn").pid > 0 ? s.Status("stubborn").pid : pid_sleep_group;
    if (t > 0.3 && t <= 0.5 && pid_sleep_group > 0) running_before_stop = RunningInGroup(pid_sleep_group);
    if (t > 0.5) s.RequestStop("test");
  });
  EXPECT_GE(running_before_stop, 2);  // the shell and its sleep: what the check below must see end
  EXPECT_EQ(r.rc, 0) << r.err;  // the stubborn one is not required
  std::ifstream in(order);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), "stubborn\nsecond\nfirst\n");  // started order: first, second, stubborn
  EXPECT_NE(r.err.find("launch: stubborn: did not stop within its grace time of 0.50 s: SIGKILL"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("launch: stubborn: stopped (killed by SIGKILL"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not a clean stop"), std::string::npos);
  EXPECT_LT(r.seconds, 0.5 + 0.5 + 1.5);
  // Its whole process group went with it: the sleep child too is killed (gone, or a zombie left
  // for init to reap).
  EXPECT_FALSE(Alive(pid_sleep_group));
  ASSERT_GT(pid_sleep_group, 0);
  int running = -1;
  for (int i = 0; i < 100 && running != 0; ++i) {
    running = RunningInGroup(pid_sleep_group);
    if (running != 0) ::usleep(20000);
  }
  EXPECT_EQ(running, 0) << "processes of the stubborn one's group still run";
  fs::remove_all(dir);
}

TEST(Supervisor, AKillAfterTheGraceTimeFailsARequiredProcess) {
  ProcessSpec stubborn = Sh("stubborn", "trap '' INT; sleep 30");
  stubborn.stop_grace_s = 0.3;
  const RunResult r = RunAll({stubborn}, {}, [](Supervisor& s, double t) {
    if (t > 0.3) s.RequestStop("test");
  });
  EXPECT_EQ(r.rc, 1);
}

TEST(Supervisor, ReadyExitedAndReadyLineGateTheNextStart) {
  const fs::path dir = TempDir("ready");
  const std::string trace = (dir / "trace").string();
  ProcessSpec prepare = Sh("prepare", "sleep 0.3; echo prepared >> " + trace);
  prepare.ready = ReadyKind::kExited;
  ProcessSpec server = Sh("server", "sleep 0.2; echo listening; echo server >> " + trace +
                                         "; trap 'exit 0' INT; while :; do sleep 0.05; done");
  server.ready = ReadyKind::kLine;
  server.ready_pattern = "^listening$";
  ProcessSpec client = Sh("client", "echo client >> " + trace + "; sleep 0.1");
  client.exit_stops_all = true;
  const RunResult r = RunAll({prepare, server, client});
  EXPECT_EQ(r.rc, 0) << r.err;
  std::ifstream in(trace);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), "prepared\nserver\nclient\n");
  EXPECT_NE(r.err.find("launch: prepare: ready after"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("launch: server: ready after"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("stopping (client ended (exit_stops_all))"), std::string::npos) << r.err;
  EXPECT_EQ(Find(r, "server").state, State::kStopped);
  EXPECT_EQ(Find(r, "client").state, State::kExited);
  fs::remove_all(dir);
}

TEST(Supervisor, AStopWhileAProcessStartsIsNoFailure) {
  ProcessSpec slow = Sh("slow", "trap 'exit 0' INT; while :; do sleep 0.05; done");
  slow.ready = ReadyKind::kLine;
  slow.ready_pattern = "never printed";
  ProcessSpec later = Sh("later", "echo should not start");
  const RunResult r = RunAll({slow, later}, {}, [](Supervisor& s, double t) {
    if (t > 0.2) s.RequestStop("Ctrl-C");
  });
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(Find(r, "slow").state, State::kStopped);
  EXPECT_EQ(Find(r, "later").runs, 0);
}

TEST(Supervisor, NotReadyInTimeStopsTheDeployment) {
  ProcessSpec silent = Sh("silent", "trap 'exit 0' INT; while :; do sleep 0.05; done");
  silent.ready = ReadyKind::kLine;
  silent.ready_pattern = "never printed";
  silent.ready_timeout_s = 0.3;
  ProcessSpec later = Sh("later", "echo should not start");
  const RunResult r = RunAll({silent, later});
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("launch: silent: not ready after 0.30 s (ready = line never printed)"), std::string::npos) << r.err;
  EXPECT_EQ(Find(r, "later").state, State::kWaiting);
  EXPECT_EQ(Find(r, "later").runs, 0);
  EXPECT_EQ(r.out.find("should not start"), std::string::npos);
}

TEST(Supervisor, MissingProgramsAreSkippedOrStopEverythingBeforeItStarts) {
  ProcessSpec ok = Sh("ok", "echo ran");
  ProcessSpec optional = ok;
  optional.name = "optional";
  optional.argv = {"/nonexistent/ratslam"};
  optional.if_missing = IfMissing::kSkip;
  RunResult r = RunAll({ok, optional});
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(Find(r, "optional").state, State::kSkipped);
  EXPECT_NE(r.err.find("launch: optional: skipped: program '/nonexistent/ratslam' not found (test.deploy:1); if_missing = skip"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("ok       | ran"), std::string::npos) << r.out;

  ProcessSpec needed = optional;
  needed.name = "needed";
  needed.if_missing = IfMissing::kError;
  r = RunAll({ok, needed});
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("launch: error: needed: program '/nonexistent/ratslam' not found"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nothing started"), std::string::npos);
  EXPECT_EQ(Find(r, "ok").runs, 0);
}

TEST(Supervisor, PassesTheBusUrlAndWritesTheStatusFile) {
  const fs::path dir = TempDir("status");
  SupervisorOptions o;
  o.lcm_url = "udpm://239.255.76.67:7999?ttl=1";
  o.status_file = (dir / "status").string();
  ProcessSpec p = Sh("env", "echo \"url=$LCM_DEFAULT_URL\"");
  std::string seen_running;
  const RunResult r = RunAll({p}, o);
  EXPECT_NE(r.out.find("env | url=udpm://239.255.76.67:7999?ttl=1\n"), std::string::npos) << r.out;
  std::ifstream in(o.status_file);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_NE(ss.str().find("env\texited\t0\t1\t0\texit code 0\n"), std::string::npos) << ss.str();
  fs::remove_all(dir);
}

TEST(Supervisor, ChildrenGetOnlyTheirOwnOutputDescriptors) {
  const fs::path dir = TempDir("fds");
  ProcessSpec a = Sh("a", "ls /proc/self/fd | sort -n | tr '\\n' ' '");
  a.log_file = (dir / "a.log").string();
  ProcessSpec b = a;
  b.name = "b";
  b.log_file = (dir / "b.log").string();
  const RunResult r = RunAll({a, b});
  // 0 1 2, and 3: the folder ls reads; no log file, no other process's pipe.
  EXPECT_NE(r.out.find("a | 0 1 2 3 \n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("b | 0 1 2 3 \n"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(Supervisor, StopAfterADuration) {
  ProcessSpec p = Sh("long", "trap 'exit 0' INT; while :; do sleep 0.05; done");
  SupervisorOptions o;
  o.stop_after_s = 0.4;
  const RunResult r = RunAll({p}, o);
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_GE(r.seconds, 0.4);
  EXPECT_LT(r.seconds, 2);
  EXPECT_NE(r.err.find("stopping (--duration-s 0.40 s reached)"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace snapnav::launch
