#pragma once
// SIGINT/SIGTERM handling: the first signal asks the handle loop to stop.

namespace snapnav::glue {

void InstallShutdownHandlers();
bool ShutdownRequested();
void RequestShutdown();

}  // namespace snapnav::glue
