#include "supervisor.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <regex>
#include <sstream>

extern char** environ;

namespace snapnav::launch {
namespace {

volatile std::sig_atomic_t g_stop_signals = 0;
volatile std::sig_atomic_t g_status_signals = 0;
int g_wake_fd[2] = {-1, -1};

extern "C" void OnLauncherSignal(int sig) {
  const int saved = errno;
  if (sig == SIGINT || sig == SIGTERM) ++g_stop_signals;
  if (sig == SIGUSR1) ++g_status_signals;
  if (g_wake_fd[1] >= 0) {
    const char c = 0;
    [[maybe_unused]] const ssize_t n = ::write(g_wake_fd[1], &c, 1);
  }
  errno = saved;
}

int64_t MonotonicUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::string Seconds(double s) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(s < 10 ? 2 : 1) << s << " s";
  return o.str();
}

void SetNonBlocking(int fd) { ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK); }

constexpr size_t kMaxLineBytes = 64 * 1024;  // a longer line is cut into pieces
constexpr double kDrainTimeoutS = 2.0;       // output of an ended process, if a grandchild keeps the pipe

}  // namespace

ExitStatus ExitStatus::FromWaitStatus(int wstatus) {
  ExitStatus s;
  if (WIFSIGNALED(wstatus)) {
    s.signaled = true;
    s.signal = WTERMSIG(wstatus);
    s.core = WCOREDUMP(wstatus);
  } else {
    s.code = WEXITSTATUS(wstatus);
  }
  return s;
}

std::string Describe(const ExitStatus& status) {
  if (!status.signaled) return "exit code " + std::to_string(status.code);
  return "killed by " + SignalName(status.signal) + (status.core ? " (core dumped)" : "");
}

double RestartDelay(const ProcessSpec& spec, int restarts_done) {
  const double d = spec.restart_delay_s * std::pow(2.0, std::min(restarts_done, 30));
  return std::min(d, spec.restart_delay_max_s);
}

RestartDecision DecideRestart(const ProcessSpec& spec, const ExitStatus& status, int restarts_done) {
  RestartDecision d;
  const std::string policy = std::string("restart = ") + RestartPolicyName(spec.restart);
  if (spec.restart == RestartPolicy::kNever || (spec.restart == RestartPolicy::kOnFailure && status.success())) {
    d.why = policy;
    return d;
  }
  if (restarts_done >= spec.restart_limit) {
    d.why = "restart limit " + std::to_string(spec.restart_limit) + " reached";
    return d;
  }
  d.restart = true;
  d.delay_s = RestartDelay(spec, restarts_done);
  d.why = policy + ", restart " + std::to_string(restarts_done + 1) + " of " + std::to_string(spec.restart_limit);
  return d;
}

const char* StateName(State state) {
  switch (state) {
    case State::kWaiting: return "waiting";
    case State::kStarting: return "starting";
    case State::kRunning: return "running";
    case State::kRestarting: return "restarting";
    case State::kExited: return "exited";
    case State::kFailed: return "failed";
    case State::kStopping: return "stopping";
    case State::kStopped: return "stopped";
    case State::kSkipped: return "skipped";
  }
  return "?";
}

struct Supervisor::Child {
  size_t slot = 0;
  pid_t pid = -1;
  int fd[2] = {-1, -1};  // stdout, stderr read ends
  std::string partial[2];
  bool after_cr[2] = {false, false};
  bool reaped = false;
  ExitStatus status;
  double started_s = 0;
  double reaped_s = 0;
  std::string exec_error;  // execvp failed: why
  bool live() const { return !reaped; }
  bool drained() const { return fd[0] < 0 && fd[1] < 0; }
};

struct Supervisor::Slot {
  ProcessSpec spec;
  State state = State::kWaiting;
  Child* child = nullptr;  // the current run (owned by children_)
  int runs = 0;
  int restarts = 0;
  double restart_due_s = 0;
  double started_s = 0;
  std::string last_exit;
  bool ready_line_seen = false;
  bool killed_after_grace = false;
  double stop_sent_s = 0;
  std::optional<std::regex> echo_re, ready_re;
  std::ofstream log;
};

void InstallSignalHandlers() {
  if (g_wake_fd[0] < 0) {
    if (::pipe2(g_wake_fd, O_CLOEXEC | O_NONBLOCK) != 0) throw std::runtime_error("pipe2: " + std::string(std::strerror(errno)));
  }
  struct sigaction sa {};
  sa.sa_handler = OnLauncherSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  for (const int sig : {SIGINT, SIGTERM, SIGUSR1, SIGCHLD}) sigaction(sig, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
}

Supervisor::Supervisor(std::vector<ProcessSpec> processes, SupervisorOptions options, std::ostream& out,
                       std::ostream& err)
    : options_(std::move(options)), out_(out), err_(err) {
  for (auto& p : processes) {
    auto slot = std::make_unique<Slot>();
    name_width_ = std::max(name_width_, p.name.size());
    if (p.echo == EchoMode::kMatch) slot->echo_re.emplace(p.echo_pattern);
    if (p.ready == ReadyKind::kLine) slot->ready_re.emplace(p.ready_pattern);
    slot->spec = std::move(p);
    slots_.push_back(std::move(slot));
  }
  start_us_ = MonotonicUs();
}

Supervisor::~Supervisor() {
  for (auto& c : children_) {
    if (c->live()) {
      ::kill(-c->pid, SIGKILL);
      int st = 0;
      ::waitpid(c->pid, &st, 0);
    }
    for (int& fd : c->fd) {
      if (fd >= 0) ::close(fd);
    }
  }
}

double Supervisor::Now() const { return (MonotonicUs() - start_us_) * 1e-6; }
double Supervisor::elapsed_s() const { return Now(); }

void Supervisor::Say(const std::string& text) { err_ << "launch: " << text << std::endl; }

void Supervisor::SayAbout(Slot& slot, const std::string& text) {
  Say(slot.spec.name + ": " + text);
  if (slot.log.is_open()) slot.log << "launch: " << slot.spec.name << ": " << text << std::endl;
  dirty_ = true;
}

void Supervisor::RequestStop(const std::string& why) {
  if (stopping_) return;
  stopping_ = true;
  stop_reason_ = why;
  stop_index_ = slots_.size();
  Say("stopping (" + why + "): reverse start order, each with its stop signal, SIGKILL after its grace time");
  for (auto& s : slots_) {
    if (s->state == State::kRestarting) {
      s->state = State::kStopped;
      SayAbout(*s, "restart cancelled");
    }
  }
  dirty_ = true;
}

std::vector<ProcessStatus> Supervisor::Status() const {
  std::vector<ProcessStatus> out;
  const double now = Now();
  for (const auto& s : slots_) {
    ProcessStatus p;
    p.name = s->spec.name;
    p.state = s->state;
    p.runs = s->runs;
    p.restarts = s->restarts;
    p.last_exit = s->last_exit;
    if (s->child && s->child->live()) {
      p.pid = s->child->pid;
      p.up_s = now - s->child->started_s;
    }
    out.push_back(p);
  }
  return out;
}

ProcessStatus Supervisor::Status(const std::string& name) const {
  for (const auto& p : Status()) {
    if (p.name == name) return p;
  }
  throw std::invalid_argument("no process '" + name + "' in this deployment");
}

bool Supervisor::Preflight() {
  bool ok = true;
  for (auto& s : slots_) {
    const std::string& program = s->spec.argv.at(0);
    if (FindProgram(program)) continue;
    const std::string why = "program '" + program + "' not found" +
                            (program.find('/') != std::string::npos ? "" : " on the PATH") + " (" + s->spec.where + ")";
    if (s->spec.if_missing == IfMissing::kSkip) {
      s->state = State::kSkipped;
      s->last_exit = "not installed";
      Say(s->spec.name + ": skipped: " + why + "; if_missing = skip");
    } else {
      Say("error: " + s->spec.name + ": " + why);
      ok = false;
    }
  }
  if (!ok) Say("nothing started: install or build the missing programs, or set if_missing = skip for them");
  return ok;
}

void Supervisor::Start(Slot& slot, double now) {
  const ProcessSpec& spec = slot.spec;
  if (!spec.log_file.empty() && !slot.log.is_open()) {
    const auto parent = std::filesystem::path(spec.log_file).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
    slot.log.open(spec.log_file, std::ios::app);
    if (!slot.log) throw std::runtime_error(spec.name + ": cannot open log_file '" + spec.log_file + "'");
  }
  // Everything the child needs, before fork: argv, the environment.
  std::vector<std::string> env_strings;
  for (char** e = environ; *e; ++e) {
    if (!options_.lcm_url.empty() && std::strncmp(*e, "LCM_DEFAULT_URL=", 16) == 0) continue;
    env_strings.emplace_back(*e);
  }
  if (!options_.lcm_url.empty()) env_strings.push_back("LCM_DEFAULT_URL=" + options_.lcm_url);
  std::vector<char*> envp, argv;
  for (auto& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);
  std::vector<std::string> args = spec.argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  int out_pipe[2], err_pipe[2], exec_pipe[2];
  if (::pipe2(out_pipe, O_CLOEXEC) != 0 || ::pipe2(err_pipe, O_CLOEXEC) != 0 || ::pipe2(exec_pipe, O_CLOEXEC) != 0) {
    throw std::runtime_error("pipe2: " + std::string(std::strerror(errno)));
  }
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork: " + std::string(std::strerror(errno)));
  if (pid == 0) {
    // The child: own process group, SIGTERM when the launcher dies, default signals, the pipes.
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(126);
    sigset_t all;
    sigemptyset(&all);
    ::sigprocmask(SIG_SETMASK, &all, nullptr);
    for (int sig = 1; sig < NSIG; ++sig) {
      if (sig != SIGKILL && sig != SIGSTOP) std::signal(sig, SIG_DFL);
    }
    const int devnull = ::open("/dev/null", O_RDONLY);
    if (devnull >= 0) ::dup2(devnull, 0);
    ::dup2(out_pipe[1], 1);
    ::dup2(err_pipe[1], 2);
    // Nothing else of the launcher's (its log files, other processes' pipes) leaks into the child;
    // the exec pipe closes itself on exec.
    const unsigned exec_fd = static_cast<unsigned>(exec_pipe[1]);
    if (exec_fd > 3) ::close_range(3, exec_fd - 1, 0);
    ::close_range(exec_fd + 1, ~0U, 0);
    ::execvpe(argv[0], argv.data(), envp.data());
    const int e = errno;
    [[maybe_unused]] const ssize_t n = ::write(exec_pipe[1], &e, sizeof e);
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // also here, so a stop signal can never miss the group
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  ::close(exec_pipe[1]);
  int exec_errno = 0;
  ssize_t n;
  do {
    n = ::read(exec_pipe[0], &exec_errno, sizeof exec_errno);
  } while (n < 0 && errno == EINTR);
  ::close(exec_pipe[0]);

  auto child = std::make_unique<Child>();
  for (size_t i = 0; i < slots_.size(); ++i) {
    if (slots_[i].get() == &slot) child->slot = i;
  }
  child->pid = pid;
  child->fd[0] = out_pipe[0];
  child->fd[1] = err_pipe[0];
  SetNonBlocking(child->fd[0]);
  SetNonBlocking(child->fd[1]);
  child->started_s = now;
  if (n == static_cast<ssize_t>(sizeof exec_errno)) child->exec_error = std::strerror(exec_errno);
  slot.child = child.get();
  children_.push_back(std::move(child));
  ++slot.runs;
  slot.started_s = now;
  slot.ready_line_seen = false;
  slot.killed_after_grace = false;
  slot.state = State::kRunning;
  if (slot.log.is_open()) {
    slot.log << "--- launch: " << spec.name << " run " << slot.runs << ", pid " << pid << ": " << spec.CommandLine()
             << std::endl;
  }
  if (!slot.child->exec_error.empty()) {
    SayAbout(slot, "cannot execute '" + spec.argv[0] + "': " + slot.child->exec_error);
  } else {
    SayAbout(slot, std::string(slot.runs == 1 ? "started" : "restarted") + " (pid " + std::to_string(pid) +
                       (slot.restarts > 0 ? ", restart " + std::to_string(slot.restarts) + " of " +
                                                std::to_string(spec.restart_limit)
                                          : std::string()) +
                       ")");
  }
}

void Supervisor::AdvanceStart(double now) {
  while (!stopping_ && gate_ < 0 && next_ < slots_.size()) {
    const size_t i = next_++;
    Slot& s = *slots_[i];
    if (s.state == State::kSkipped) continue;
    Start(s, now);
    if (s.spec.ready != ReadyKind::kNone && s.child->exec_error.empty()) {
      gate_ = static_cast<int>(i);
      gate_since_s_ = now;
      s.state = State::kStarting;
    }
  }
}

void Supervisor::CheckGate(double now) {
  if (gate_ < 0) return;
  Slot& s = *slots_[static_cast<size_t>(gate_)];
  if (stopping_) {  // nothing more starts; a process stopped while it started has not failed
    gate_ = -1;
    if (s.state == State::kStarting) s.state = State::kRunning;
    return;
  }
  const ProcessSpec& spec = s.spec;
  bool ready = false;
  std::string what;
  switch (spec.ready) {
    case ReadyKind::kNone: ready = true; break;
    case ReadyKind::kDelay:
      ready = now - gate_since_s_ >= spec.ready_delay_s;
      break;
    case ReadyKind::kLine:
      ready = s.ready_line_seen;
      what = "printed a line matching '" + spec.ready_pattern + "'";
      break;
    case ReadyKind::kFile:
      ready = ::access(spec.ready_pattern.c_str(), F_OK) == 0;
      what = "wrote " + spec.ready_pattern;
      break;
    case ReadyKind::kExited:
      ready = s.state == State::kExited;
      what = "finished";
      break;
  }
  const bool ended = s.state == State::kExited || s.state == State::kFailed || s.state == State::kStopped;
  if (ready) {
    gate_ = -1;
    if (s.state == State::kStarting) s.state = State::kRunning;
    if (!what.empty()) SayAbout(s, "ready after " + Seconds(now - gate_since_s_) + " (" + what + ")");
    dirty_ = true;
    return;
  }
  std::string failure;
  if (ended) {
    failure = "ended before it was ready (ready = " + std::string(ReadyKindName(spec.ready)) + ")";
  } else if (spec.ready != ReadyKind::kDelay && now - gate_since_s_ >= spec.ready_timeout_s) {
    failure = "not ready after " + Seconds(spec.ready_timeout_s) + " (ready = " + ReadyKindName(spec.ready) +
              (spec.ready_pattern.empty() ? "" : " " + spec.ready_pattern) + ")";
  }
  if (failure.empty()) return;
  gate_ = -1;
  SayAbout(s, failure);
  if (spec.required) {
    failed_ = true;
    RequestStop(spec.name + " was not ready");
  } else if (s.state == State::kStarting) {
    s.state = State::kRunning;
  }
}

void Supervisor::AdvanceStop(double now) {
  if (!stopping_) return;
  if (stop_slot_ >= 0) {
    Slot& s = *slots_[static_cast<size_t>(stop_slot_)];
    if (s.child && s.child->live()) {
      if (now >= stop_deadline_s_ && !s.killed_after_grace) {
        ::kill(-s.child->pid, SIGKILL);
        s.killed_after_grace = true;
        SayAbout(s, "did not stop within its grace time of " + Seconds(s.spec.stop_grace_s) + ": SIGKILL");
      }
      return;
    }
    stop_slot_ = -1;
  }
  while (stop_index_ > 0) {
    const size_t i = --stop_index_;
    Slot& s = *slots_[i];
    if (!s.child || !s.child->live()) continue;
    ::kill(-s.child->pid, s.spec.stop_signal);
    s.state = State::kStopping;
    s.stop_sent_s = now;
    stop_slot_ = static_cast<int>(i);
    stop_deadline_s_ = now + s.spec.stop_grace_s;
    SayAbout(s, "sent " + SignalName(s.spec.stop_signal) + " (grace " + Seconds(s.spec.stop_grace_s) + ")");
    return;
  }
}

void Supervisor::KillAll(const std::string& why) {
  Say(why + ": SIGKILL to every process");
  for (auto& s : slots_) {
    if (s->child && s->child->live()) {
      ::kill(-s->child->pid, SIGKILL);
      s->state = State::kStopping;
      s->stop_sent_s = Now();
      s->killed_after_grace = true;
    }
  }
  stop_index_ = 0;
}

void Supervisor::EmitLine(Slot& slot, bool err_stream, const std::string& line) {
  if (slot.log.is_open()) slot.log << line << '\n';
  if (slot.ready_re && !slot.ready_line_seen && std::regex_search(line, *slot.ready_re)) slot.ready_line_seen = true;
  const bool echo = slot.spec.echo == EchoMode::kAll ||
                    (slot.spec.echo == EchoMode::kMatch && std::regex_search(line, *slot.echo_re));
  if (!echo) return;
  std::ostream& o = err_stream ? err_ : out_;
  o << std::left << std::setw(static_cast<int>(name_width_)) << slot.spec.name << " | " << line << '\n';
}

void Supervisor::ReadFrom(Child& child, bool err_stream) {
  int& fd = child.fd[err_stream ? 1 : 0];
  std::string& partial = child.partial[err_stream ? 1 : 0];
  Slot& slot = *slots_[child.slot];
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) {
      partial.append(buf, static_cast<size_t>(n));
      // A line ends at \n, \r\n or a lone \r (progress that rewrites itself in a terminal).
      size_t start = 0;
      bool& after_cr = child.after_cr[err_stream ? 1 : 0];
      for (size_t end; (end = partial.find_first_of("\r\n", start)) != std::string::npos; start = end + 1) {
        const bool newline_after_cr = partial[end] == '\n' && after_cr && end == start;
        after_cr = partial[end] == '\r';
        if (!newline_after_cr) EmitLine(slot, err_stream, partial.substr(start, end - start));
      }
      partial.erase(0, start);
      while (partial.size() > kMaxLineBytes) {
        EmitLine(slot, err_stream, partial.substr(0, kMaxLineBytes));
        partial.erase(0, kMaxLineBytes);
      }
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
    // End of file (or an error): what is left is the last line.
    if (!partial.empty()) EmitLine(slot, err_stream, partial);
    partial.clear();
    ::close(fd);
    fd = -1;
    return;
  }
}

void Supervisor::PollOutput(int timeout_ms) {
  std::vector<pollfd> fds;
  std::vector<std::pair<Child*, bool>> owners;
  if (g_wake_fd[0] >= 0) {
    fds.push_back({g_wake_fd[0], POLLIN, 0});
    owners.emplace_back(nullptr, false);
  }
  for (auto& c : children_) {
    for (int k = 0; k < 2; ++k) {
      if (c->fd[k] >= 0) {
        fds.push_back({c->fd[k], POLLIN, 0});
        owners.emplace_back(c.get(), k == 1);
      }
    }
  }
  const int n = ::poll(fds.data(), fds.size(), timeout_ms);
  if (n <= 0) return;
  for (size_t i = 0; i < fds.size(); ++i) {
    if (!(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
    if (!owners[i].first) {
      char drain[64];
      while (::read(g_wake_fd[0], drain, sizeof drain) > 0) {
      }
      continue;
    }
    ReadFrom(*owners[i].first, owners[i].second);
  }
  out_.flush();
  err_.flush();
}

void Supervisor::Reap(double now) {
  for (auto& c : children_) {
    if (!c->live()) continue;
    int wstatus = 0;
    const pid_t r = ::waitpid(c->pid, &wstatus, WNOHANG);
    if (r != c->pid) continue;
    c->reaped = true;
    c->reaped_s = now;
    c->status = ExitStatus::FromWaitStatus(wstatus);
    ::kill(-c->pid, SIGKILL);  // what it left behind in its group
    // Its last output first, so the exit message follows it.
    for (int k = 0; k < 2; ++k) {
      if (c->fd[k] >= 0) ReadFrom(*c, k == 1);
    }
    Slot& s = *slots_[c->slot];
    if (s.child == c.get()) OnExit(s, *c, now);
  }
  // Drop ended children whose output is read (or that a grandchild keeps open too long).
  for (auto it = children_.begin(); it != children_.end();) {
    Child& c = **it;
    if (!c.live() && !c.drained() && now - c.reaped_s > kDrainTimeoutS) {
      for (int& fd : c.fd) {
        if (fd >= 0) ::close(fd);
        fd = -1;
      }
    }
    if (!c.live() && c.drained()) {
      Slot& s = *slots_[c.slot];
      if (s.child == &c) s.child = nullptr;
      it = children_.erase(it);
    } else {
      ++it;
    }
  }
}

void Supervisor::OnExit(Slot& slot, Child& child, double now) {
  const ProcessSpec& spec = slot.spec;
  const ExitStatus& st = child.status;
  const double up = now - child.started_s;
  slot.last_exit = child.exec_error.empty() ? Describe(st) : "cannot execute: " + child.exec_error;
  const std::string after = " after " + Seconds(up);
  if (slot.state == State::kStopping) {
    const bool clean = !slot.killed_after_grace && (st.success() || (st.signaled && st.signal == spec.stop_signal));
    slot.state = State::kStopped;
    SayAbout(slot, "stopped (" + slot.last_exit + ", " + Seconds(now - slot.stop_sent_s) +
                       " after the stop signal)" + (clean ? "" : ": not a clean stop"));
    if (!clean && spec.required) failed_ = true;
    return;
  }
  if (stopping_) {
    slot.state = st.success() ? State::kExited : State::kFailed;
    SayAbout(slot, "ended by itself while stopping (" + slot.last_exit + ")" + after);
    if (!st.success() && spec.required) failed_ = true;
    return;
  }
  if (!child.exec_error.empty()) {
    slot.state = State::kFailed;
    if (spec.required) {
      failed_ = true;
      RequestStop("required process " + spec.name + " cannot be executed");
    }
    return;
  }
  const RestartDecision d = DecideRestart(spec, st, slot.restarts);
  if (d.restart) {
    slot.state = State::kRestarting;
    slot.restart_due_s = now + d.delay_s;
    SayAbout(slot, "ended (" + slot.last_exit + ")" + after + "; restarting in " + Seconds(d.delay_s) + " (" + d.why + ")");
    return;
  }
  slot.state = st.success() ? State::kExited : State::kFailed;
  SayAbout(slot, std::string(st.success() ? "finished" : "FAILED") + " (" + slot.last_exit + ")" + after + "; " + d.why +
                     (spec.required ? "" : " (not required)"));
  if (!st.success() && spec.required) {
    failed_ = true;
    RequestStop("required process " + spec.name + " failed");
  } else if (spec.exit_stops_all) {
    RequestStop(spec.name + " ended (exit_stops_all)");
  }
}

bool Supervisor::Finished() const {
  for (const auto& c : children_) {
    if (c->live() || !c->drained()) return false;
  }
  if (stopping_) return stop_index_ == 0 && stop_slot_ < 0;
  if (next_ < slots_.size() || gate_ >= 0) return false;
  for (const auto& s : slots_) {
    if (s->state == State::kRestarting) return false;
  }
  return true;
}

void Supervisor::PrintStatus(const std::string& title) {
  std::ostringstream o;
  o << "launch: " << title << " at " << Seconds(Now()) << "\n";
  for (const auto& p : Status()) {
    o << "launch:   " << std::left << std::setw(static_cast<int>(name_width_)) << p.name << "  " << std::setw(10)
      << StateName(p.state);
    if (p.pid > 0) o << "  pid " << std::setw(7) << p.pid << "  up " << std::setw(8) << Seconds(p.up_s);
    o << "  runs " << p.runs << "  restarts " << p.restarts;
    if (!p.last_exit.empty()) o << "  last: " << p.last_exit;
    o << "\n";
  }
  err_ << o.str() << std::flush;
}

void Supervisor::WriteStatusFile() {
  if (options_.status_file.empty()) return;
  const std::string tmp = options_.status_file + ".tmp";
  {
    std::ofstream f(tmp, std::ios::trunc);
    f << "# launch status at " << std::fixed << std::setprecision(1) << Now() << " s"
      << (stopping_ ? ", stopping: " + stop_reason_ : std::string()) << "\n# name\tstate\tpid\truns\trestarts\tlast_exit\n";
    for (const auto& p : Status()) {
      f << p.name << '\t' << StateName(p.state) << '\t' << p.pid << '\t' << p.runs << '\t' << p.restarts << '\t'
        << (p.last_exit.empty() ? "-" : p.last_exit) << '\n';
    }
  }
  std::filesystem::rename(tmp, options_.status_file);
}

int Supervisor::Run() {
  start_us_ = MonotonicUs();
  next_status_s_ = options_.status_every_s;
  if (!Preflight()) {
    failed_ = true;
    WriteStatusFile();
    return 1;
  }
  int stops_seen = g_stop_signals, status_seen = g_status_signals;
  for (;;) {
    const double now = Now();
    if (g_stop_signals != stops_seen) {
      const int n = g_stop_signals - stops_seen;
      stops_seen = g_stop_signals;
      if (stopping_ || n > 1) {
        KillAll("second stop request");
      } else {
        RequestStop("signal");
      }
    }
    if (g_status_signals != status_seen) {
      status_seen = g_status_signals;
      status_requested_ = true;
    }
    if (options_.stop_after_s > 0 && now >= options_.stop_after_s) RequestStop("--duration-s " + Seconds(options_.stop_after_s) + " reached");
    if (on_tick) on_tick(*this, now);
    AdvanceStart(now);
    if (!stopping_) {
      for (auto& s : slots_) {
        if (s->state == State::kRestarting && now >= s->restart_due_s) {
          ++s->restarts;
          Start(*s, now);
        }
      }
    }
    AdvanceStop(now);
    PollOutput(options_.poll_ms);
    const double after = Now();
    Reap(after);
    CheckGate(after);
    AdvanceStop(after);
    if (status_requested_ || (options_.status_every_s > 0 && after >= next_status_s_)) {
      PrintStatus(status_requested_ ? "status (requested)" : "status");
      status_requested_ = false;
      while (options_.status_every_s > 0 && next_status_s_ <= after) next_status_s_ += options_.status_every_s;
    }
    if (dirty_) {
      WriteStatusFile();
      dirty_ = false;
    }
    for (auto& s : slots_) {
      if (s->log.is_open()) s->log.flush();
    }
    if (Finished()) break;
  }
  for (auto& s : slots_) {
    if (s->state == State::kWaiting && stopping_) s->last_exit = "not started";
  }
  PrintStatus(std::string("final status") + (failed_ ? " (a required process failed)" : ""));
  WriteStatusFile();
  return failed_ ? 1 : 0;
}

}  // namespace snapnav::launch
