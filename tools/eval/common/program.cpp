#include "program.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace snapnav::eval {
namespace {

using Clock = std::chrono::steady_clock;

std::string Quote(const std::string& s) { return s.find_first_of(" \t'\"") == std::string::npos ? s : "'" + s + "'"; }

}  // namespace

std::string LastLines(const std::string& path, size_t n) {
  std::ifstream in(path);
  std::deque<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    std::replace(line.begin(), line.end(), '\r', '\n');
    if (const auto cut = line.rfind('\n'); cut != std::string::npos) line = line.substr(cut + 1);
    if (line.empty()) continue;
    lines.push_back(line);
    if (lines.size() > n) lines.pop_front();
  }
  std::string out;
  for (const auto& l : lines) out += "\n    " + l;
  return out.empty() ? "\n    (no output)" : out;
}

std::string FindProgram(const std::string& name, const std::string& package) {
  auto executable = [](const std::string& p) {
    struct stat st {};
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(p.c_str(), X_OK) == 0;
  };
  if (name.find('/') != std::string::npos) {
    if (executable(name)) return name;
    throw std::runtime_error(name + ": no such executable (install Debian's " + package + ")");
  }
  const char* path_env = std::getenv("PATH");
  std::istringstream dirs(path_env ? path_env : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + name;
    if (executable(candidate)) return candidate;
  }
  throw std::runtime_error(name + " not found on PATH (install Debian's " + package + ")");
}

ProgramResult RunProgram(const std::vector<std::string>& argv, const std::string& log_path, double timeout_s) {
  const int log_fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) throw std::runtime_error("cannot write " + log_path + ": " + std::strerror(errno));
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const auto t0 = Clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(log_fd);
    throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  }
  if (pid == 0) {
    const int null_fd = ::open("/dev/null", O_RDONLY);
    if (null_fd >= 0) ::dup2(null_fd, 0);
    ::dup2(log_fd, 1);
    ::dup2(log_fd, 2);
    ::execv(args[0], args.data());
    const std::string msg = std::string("exec ") + args[0] + ": " + std::strerror(errno) + "\n";
    (void)!::write(2, msg.data(), msg.size());
    ::_exit(127);
  }
  ::close(log_fd);
  ProgramResult result;
  for (;;) {
    const pid_t r = ::waitpid(pid, &result.status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw std::runtime_error(std::string("waitpid failed: ") + std::strerror(errno));
    if (std::chrono::duration<double>(Clock::now() - t0).count() > timeout_s) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &result.status, 0);
      throw std::runtime_error(argv[0] + " did not finish within " + std::to_string(static_cast<int>(timeout_s)) +
                               " s and was killed; its output is in " + log_path + LastLines(log_path, 10));
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  result.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return result;
}

std::string CommandLine(const std::vector<std::string>& argv) {
  std::string s;
  for (const auto& a : argv) s += (s.empty() ? "" : " ") + Quote(a);
  return s;
}

void CheckExit(const ProgramResult& r, const std::vector<std::string>& argv, const std::string& log_path) {
  if (WIFEXITED(r.status) && WEXITSTATUS(r.status) == 0) return;
  const std::string how = WIFEXITED(r.status) ? "exited with code " + std::to_string(WEXITSTATUS(r.status))
                                              : "was killed by signal " + std::to_string(WTERMSIG(r.status));
  throw std::runtime_error("`" + CommandLine(argv) + "` " + how + "; its output is in " + log_path +
                           ", last lines:" + LastLines(log_path, 12));
}

}  // namespace snapnav::eval
