# RatSLAM on the simulator with ground truth (./snapnav eval ratslam): the library the SLAM
# comparison reuses, and its thin binary. Included by tools/CMakeLists.txt: paths are relative to
# tools/.
add_library(snapnav_ratslam_eval STATIC eval/ratslam_eval.cpp)
target_include_directories(snapnav_ratslam_eval PUBLIC eval)
target_link_libraries(snapnav_ratslam_eval PUBLIC snapnav_slam_sim snapnav_ratslam snapnav_homing snapnav_plot
  PRIVATE snapnav_results opencv_imgproc)
add_executable(eval-ratslam eval/eval_ratslam_main.cpp)
target_link_libraries(eval-ratslam PRIVATE snapnav_ratslam_eval snapnav_glue_ratslam)
# bench-ratslam (./snapnav bench ratslam): ms per update at several map sizes, on one core.
add_executable(bench-ratslam bench/bench_ratslam.cpp)
target_link_libraries(bench-ratslam PRIVATE snapnav_glue_ratslam snapnav_sim_node snapnav_results opencv_imgproc)
