#include "graph_slam_config.hpp"

namespace snapnav::processes {

const char* SlamBackendName(SlamBackend b) {
  switch (b) {
    case SlamBackend::kEkf: return "ekf";
    case SlamBackend::kGraph: return "graph";
  }
  return "?";
}

std::optional<SlamBackend> ParseSlamBackend(const std::string& name) {
  if (name == "ekf") return SlamBackend::kEkf;
  if (name == "graph") return SlamBackend::kGraph;
  return std::nullopt;
}

}  // namespace snapnav::processes
