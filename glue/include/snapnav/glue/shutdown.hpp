#pragma once
// SIGINT/SIGTERM handling: the first signal asks the handle loop to stop.

namespace snapnav::glue {

void InstallShutdownHandlers();
bool ShutdownRequested();

}  // namespace snapnav::glue
