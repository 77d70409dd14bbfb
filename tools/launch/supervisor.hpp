#pragma once
// Supervision of a deployment's processes (the logic of `launch`):
//  - start them in file order, each waiting for the previous one's readiness (ready = ...);
//  - prefix every line of their stdout/stderr with the process name (stdout to out, stderr to err),
//    filtered by echo, and keep all of it in each one's log_file;
//  - restart a process that ended by policy (never / on-failure / always), with a back-off that
//    doubles up to restart_delay_max_s, at most restart_limit times;
//  - report every process's state every status_every_s, on SIGUSR1 and at the end;
//  - stop all on RequestStop() (SIGINT/SIGTERM), when a required process fails for good, when an
//    exit_stops_all process ends, or after stop_after_s: in reverse start order, each with its stop
//    signal, then SIGKILL after its grace time. A second stop request kills what is left at once.
// Each process runs in its own process group (so a stop signal reaches its children too) with
// LCM_DEFAULT_URL set to the bus URL, and gets SIGTERM if the launcher dies.

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "deployment.hpp"

namespace snapnav::launch {

struct ExitStatus {
  bool signaled = false;
  int code = 0;    // exit code (not signaled)
  int signal = 0;  // the signal that ended it (signaled)
  bool core = false;

  static ExitStatus FromWaitStatus(int wstatus);
  static ExitStatus Exited(int code) { return {false, code, 0, false}; }
  static ExitStatus Killed(int signal) { return {true, 0, signal, false}; }
  bool success() const { return !signaled && code == 0; }
};

// "exit code 3", "killed by SIGKILL", "killed by SIGSEGV (core dumped)".
std::string Describe(const ExitStatus& status);

// Back-off before restart number restarts_done + 1: restart_delay_s x 2^restarts_done, at most
// restart_delay_max_s.
double RestartDelay(const ProcessSpec& spec, int restarts_done);

// What to do after a process ended by itself (not stopped by the launcher).
struct RestartDecision {
  bool restart = false;
  double delay_s = 0;
  std::string why;  // e.g. "restart = on-failure, 1 of 3", "restart limit 3 reached"
};
RestartDecision DecideRestart(const ProcessSpec& spec, const ExitStatus& status, int restarts_done);

enum class State {
  kWaiting,     // not started yet (start order), or never started (stopped before its turn)
  kStarting,    // running, the launcher waits for it to be ready
  kRunning,
  kRestarting,  // ended, restart due after the back-off
  kExited,      // ended with exit code 0, for good
  kFailed,      // ended otherwise, for good (or could not be executed)
  kStopping,    // stop signal sent
  kStopped,     // stopped by the launcher
  kSkipped,     // its program is not installed (if_missing = skip)
};
const char* StateName(State state);

struct ProcessStatus {
  std::string name;
  State state = State::kWaiting;
  int pid = 0;        // of the current run; 0: none
  int runs = 0;       // times started
  int restarts = 0;
  double up_s = 0;    // of the current run
  std::string last_exit;  // Describe() of the last end; empty: none yet
};

struct SupervisorOptions {
  double status_every_s = 10;  // 0: only on request and at the end
  double stop_after_s = 0;     // > 0: stop the deployment after this long
  std::string status_file;     // rewritten on every change: one tab-separated line per process
  std::string lcm_url;         // LCM_DEFAULT_URL of every process; empty: inherited
  int poll_ms = 50;
};

class Supervisor {
 public:
  Supervisor(std::vector<ProcessSpec> processes, SupervisorOptions options, std::ostream& out, std::ostream& err);
  Supervisor(const Supervisor&) = delete;
  Supervisor& operator=(const Supervisor&) = delete;
  ~Supervisor();  // kills (SIGKILL) whatever still runs

  // Runs the deployment to its end. 0: every required process ended well (or was stopped
  // cleanly); 1: a required process failed, could not start, was not ready in time, or had to be
  // killed after its grace time; nothing is started (1) when a program is missing.
  int Run();

  void RequestStop(const std::string& why);

  std::vector<ProcessStatus> Status() const;
  ProcessStatus Status(const std::string& name) const;
  double elapsed_s() const;

  // Called every loop turn with the time since Run() started (tests: stop at a time, kill one).
  std::function<void(Supervisor&, double)> on_tick;

 private:
  struct Child;
  struct Slot;

  void Say(const std::string& text);
  void SayAbout(Slot& slot, const std::string& text);
  bool Preflight();
  void Start(Slot& slot, double now);
  void AdvanceStart(double now);
  void CheckGate(double now);
  void AdvanceStop(double now);
  void KillAll(const std::string& why);
  void PollOutput(int timeout_ms);
  void ReadFrom(Child& child, bool err_stream);
  void EmitLine(Slot& slot, bool err_stream, const std::string& line);
  void Reap(double now);
  void OnExit(Slot& slot, Child& child, double now);
  bool Finished() const;
  void PrintStatus(const std::string& title);
  void WriteStatusFile();
  double Now() const;

  std::vector<std::unique_ptr<Slot>> slots_;
  std::vector<std::unique_ptr<Child>> children_;  // running, or reaped with output still to drain
  SupervisorOptions options_;
  std::ostream& out_;
  std::ostream& err_;
  size_t name_width_ = 0;
  int64_t start_us_ = 0;
  size_t next_ = 0;     // next slot to start
  int gate_ = -1;       // slot whose readiness the start sequence waits for
  double gate_since_s_ = 0;
  bool stopping_ = false;
  size_t stop_index_ = 0;  // slots below this are still to be stopped
  int stop_slot_ = -1;     // slot being stopped
  double stop_deadline_s_ = 0;
  bool failed_ = false;
  bool status_requested_ = false;
  bool dirty_ = true;
  double next_status_s_ = 0;
  std::string stop_reason_;
};

// SIGINT/SIGTERM ask a running Supervisor to stop (a second one: kill at once), SIGUSR1 for a
// status report; SIGCHLD wakes it up. SIGPIPE is ignored (children get the default back).
void InstallSignalHandlers();

}  // namespace snapnav::launch
