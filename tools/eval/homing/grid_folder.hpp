#pragma once
// A lab's own image grid (issue 21): a folder in the format gridgen writes, read by
// `eval homing --grid DIR` and `eval localization --grid DIR`.
//
//   DIR/positions.csv   header "file,ix,iy,x_m,y_m,heading_rad[,utime]" (columns in any order,
//                       others ignored), one line per image: its file (relative to DIR), its grid
//                       indices and its pose (metres, radians, any fixed frame)
//   DIR/<file>          the images, all of one size: raw omni images when DIR/camera.ini has a
//                       [mirror] section (calibrate-mirror's; its `mask` too), else panoramas
//   DIR/camera.ini      [mirror] of the raw images (optional: without it the images are panoramas)
//
// Everything wrong is reported with the file and line: a missing or unreadable image, a CSV line
// that does not parse, an image of another size than the first, two images at the same indices.

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::eval {

struct GridFolderImage {
  std::string file;  // as positions.csv names it
  int line = 0;      // its line in positions.csv
  int ix = 0, iy = 0;
  nav::Pose2 pose;
  cv::Mat image;     // BGR
};

struct GridFolder {
  std::string dir;
  bool raw = false;            // raw omni images ([mirror] of camera.ini), else panoramas
  nav::MirrorModel mirror;     // raw only
  std::string mask_path;       // raw only: [mirror] mask (a relative one from DIR), "" for none
  cv::Size size;               // every image's
  int nx = 0, ny = 0;          // max index + 1
  std::vector<GridFolderImage> images;  // in positions.csv's order
  // True when every (ix, iy) of nx x ny has exactly one image.
  bool complete() const { return static_cast<int>(images.size()) == nx * ny; }
};

// Throws std::runtime_error naming the file (and line) of what is wrong.
GridFolder LoadGridFolder(const std::string& dir);

// The images as panoramas of `panorama`: raw images unwrapped with the folder's mirror (and its
// mask: `panorama_mask` gets the panoramas' mask, empty for none); panoramas checked to be of that
// size. Throws std::runtime_error naming the folder's file otherwise.
std::vector<cv::Mat> GridFolderPanoramas(const GridFolder& folder, const nav::PanoramaModel& panorama,
                                         cv::Mat* panorama_mask);

}  // namespace snapnav::eval
