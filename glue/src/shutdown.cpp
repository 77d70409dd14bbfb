#include "snapnav/glue/shutdown.hpp"

#include <csignal>

namespace snapnav::glue {
namespace {

volatile std::sig_atomic_t g_shutdown = 0;

extern "C" void OnSignal(int) { g_shutdown = 1; }

}  // namespace

void InstallShutdownHandlers() {
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

bool ShutdownRequested() { return g_shutdown != 0; }

}  // namespace snapnav::glue
