#pragma once
// The self-occlusion mask an evaluation uses with `--mask calibrated` (the default with the
// realistic camera): what calibrate-mirror finds on frames of the simulated camera, as a lab
// calibrates its own (docs/calibration.md): `frames` raw views of the scene rendered at its grid's
// positions (spread evenly over the grid, random headings: the robot moved between them), the
// mirror fitted on their mean (nav::CalibrateMirror) and the pixels that stay still over them
// (nav::SelfOcclusionMask, calibrate-mirror's defaults). The renderer's true parts are not used.

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/scene.hpp"

namespace snapnav::eval {

// The raw image's mask (image_mask.hpp: 0 = the robot's parts, 255 = usable). `note` (if given)
// gets one line for the reports ("4.1 % of the ring from 60 frames"). Throws std::runtime_error
// when the scene has no grid or no rim is found on the frames.
cv::Mat CalibratedMask(const nav::sim::Scene& scene, const nav::sim::OmniCameraOptions& camera, uint64_t seed,
                       int frames = 60, std::string* note = nullptr);

// --mask truth: the renderer's parts (OmniRenderer::PartsMask) grown by calibrate-mirror's margin
// (nav::OcclusionOptions::grow_px, 2 px): the mask a perfect calibration would find.
cv::Mat TruthMask(const cv::Mat& parts_mask);

// An evaluation's --mask: `flag` when given, else the default for `camera`: "calibrated" with the
// realistic optics (a lab calibrates its camera), "none" with the clean camera (no robot parts in view).
std::string MaskOrDefault(const std::string& flag, const nav::sim::OmniCameraOptions& camera);

}  // namespace snapnav::eval
