# Route following evaluation (./snapnav eval route; thesis 5.1.2-5.1.3, issue 6): closed loop in
# the simulator with place cells, odometry and homing. Included by tools/CMakeLists.txt: paths
# are relative to tools/.
add_library(snapnav_route_eval STATIC eval/route_eval.cpp)
target_include_directories(snapnav_route_eval PUBLIC eval)
target_link_libraries(snapnav_route_eval PUBLIC snapnav_homing_eval snapnav_places snapnav_navigator snapnav_plot
  PRIVATE snapnav_results opencv_imgproc)
add_executable(eval-route eval/eval_route_main.cpp)
target_link_libraries(eval-route PRIVATE snapnav_route_eval snapnav_sim_node snapnav_glue_places snapnav_navigator_node)
