#pragma once
// Scene files (config/scenes/*.scene): a line-based floor plan with textures.
//
//   # comment
//   name indoor13
//   texture NAME photo FILE WIDTH_M HEIGHT_M        real photograph (searched in the photo path)
//   texture NAME pattern KIND B,G,R WIDTH_M HEIGHT_M SEED   procedural (bricks, tiles, stripes, ...)
//   floor TEXTURE|- B,G,R                            floor texture (or '-' for plain colour)
//   ceiling HEIGHT_M TEXTURE|- B,G,R                 HEIGHT_M 0 means open sky (colour = sky)
//   wall X1 Y1 X2 Y2 HEIGHT_M TEXTURE                vertical rectangle, both sides visible
//   door X1 Y1 X2 Y2 HEIGHT_M TEXTURE                same as wall
//   poster X1 Y1 X2 Y2 BOTTOM_M TOP_M TEXTURE        a rectangle hung on a wall (not on the floor)
//   box CX CY SIZE_X SIZE_Y YAW_DEG HEIGHT_M TEXTURE
//   cylinder CX CY RADIUS_M HEIGHT_M TEXTURE
//   grid ORIGIN_X ORIGIN_Y SPACING_M NX NY            image-database grid (thesis Appendix A)
//   start X Y THETA_DEG                              robot start pose
//   route X,Y X,Y ...                                waypoints of the scripted driver
//   people COUNT RADIUS_M HEIGHT_M SPEED_MPS XMIN YMIN XMAX YMAX TEXTURE[,TEXTURE...]
//
// Coordinates in metres. Errors name the file and line.

#include <string>
#include <vector>

#include "snapnav/nav/sim/scene.hpp"

namespace snapnav::processes {

// Folders searched for `photo` textures: $SNAPNAV_PHOTO_PATH (colon-separated), then
// the photographs Debian's opencv-doc and mrpt-common packages ship.
std::vector<std::string> PhotoSearchPath();

// Loads and validates a scene file. Throws std::runtime_error naming file:line.
nav::sim::Scene LoadSceneFile(const std::string& path);

// The scene file for a scene name: config/scenes/NAME.scene (or NAME itself if it is a path).
std::string SceneFilePath(const std::string& name_or_path);

}  // namespace snapnav::processes
