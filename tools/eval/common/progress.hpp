#pragma once
// The progress line of a long evaluation loop on stderr: "TOOL: WHAT DONE/TOTAL", rewritten in
// place every 10 steps and ended with a newline at the last, so a log keeps one line per loop.
#include <iostream>
#include <string>

namespace snapnav::eval {

inline void Progress(const std::string& tool, const std::string& what, int done, int total) {
  if (done == total || done % 10 == 0) {
    std::cerr << tool << ": " << what << " " << done << "/" << total << (done == total ? "\n" : "\r") << std::flush;
  }
}

}  // namespace snapnav::eval
