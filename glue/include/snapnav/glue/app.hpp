#pragma once
// main() of every binary: run the app, turn an exception into a clear message
// and a non-zero exit status.

#include <functional>

namespace snapnav::glue {

// Runs `app(argc, argv)`; prints "<program>: error: <what>" and returns 1 on an
// exception, 2 on a flag error.
int RunMain(int argc, char** argv, const std::function<int(int, char**)>& app);

}  // namespace snapnav::glue
