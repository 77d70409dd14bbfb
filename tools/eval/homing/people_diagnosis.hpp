#pragma once
// eval-homing --people-diagnosis: why homing fails among people. Where the people are in each
// grid image and in the home snapshot (on the camera? filling the view?), the AAE with the
// people removed from the home view or from the current views, and the share of matched
// landmarks that lie on people. Writes people.md, people_per_image.csv and summary.json.

#include <string>

#include "landmark_compare.hpp"

namespace snapnav::eval {

// `frames`: the frames of each view for the section on fused views.
int RunPeopleDiagnosis(const LandmarkEvalSetup& setup, const std::string& scene_name, const FrameProtocol& frames,
                       const std::string& out_dir);

}  // namespace snapnav::eval
