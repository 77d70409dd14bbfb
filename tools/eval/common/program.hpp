#pragma once
// Running a program from an evaluation (icp-slam, carmen2rawlog, the raw-like log tool): found on
// PATH, its output into a log file, killed after a timeout, its failure an error that names the
// command and shows the last lines of its output.
#include <string>
#include <vector>

namespace snapnav::eval {

// `name` as run: a path if it has a slash, else the first executable of that name on PATH. Throws
// std::runtime_error naming the Debian package to install when there is none.
std::string FindProgram(const std::string& name, const std::string& package);

struct ProgramResult {
  int status = 0;  // waitpid status
  double wall_seconds = 0;
};
// Runs argv[0] with stdin from /dev/null and stdout and stderr into `log_path`; kills it after
// timeout_s (std::runtime_error).
ProgramResult RunProgram(const std::vector<std::string>& argv, const std::string& log_path, double timeout_s);
// The command as a shell would show it.
std::string CommandLine(const std::vector<std::string>& argv);
// Throws std::runtime_error (the command, how it ended, the last lines of its output) unless it
// exited with 0.
void CheckExit(const ProgramResult& r, const std::vector<std::string>& argv, const std::string& log_path);
// The last `n` lines of a file, indented, for error messages.
std::string LastLines(const std::string& path, size_t n);

}  // namespace snapnav::eval
