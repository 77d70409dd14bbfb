#pragma once
// The shape of every evaluation's main, as MRPT's apps: an app object that reads the command line
// (Initialize) and then does the work (Run). The flag table, the runs, the tables and the files
// live in the study's library, so a main only names its app and the studies can be reused.
#include "snapnav/glue/app.hpp"

namespace snapnav::eval {

// main() of an evaluation: App::Initialize(argc, argv) (false: --help was printed, exit 0), then
// App::Run()'s exit status; an exception is glue::RunMain's message and exit status.
template <typename App>
int RunApp(int argc, char** argv) {
  return glue::RunMain(argc, argv, [](int ac, char** av) {
    App app;
    if (!app.Initialize(ac, av)) return 0;
    return app.Run();
  });
}

}  // namespace snapnav::eval
