# The SLAM comparison (./snapnav eval compare, issue 8): dead reckoning, laser SLAM, RatSLAM and fused
# SLAM on simulated runs with ground truth, and the benchmark of their update times (./snapnav bench
# compare). Included by tools/CMakeLists.txt: paths are relative to tools/.
add_library(snapnav_slam_compare STATIC eval/slam_compare.cpp eval/compare_config.cpp)
target_include_directories(snapnav_slam_compare PUBLIC eval)
target_link_libraries(snapnav_slam_compare PUBLIC snapnav_slam_sim snapnav_localization_eval snapnav_fused_slam
  snapnav_slam_plot snapnav_plot snapnav_ratslam PRIVATE snapnav_fused_slam_node snapnav_laser_slam_node
  snapnav_ratslam_node snapnav_glue_places snapnav_results opencv_imgproc)
add_executable(eval-compare eval/eval_compare_main.cpp)
target_link_libraries(eval-compare PRIVATE snapnav_slam_compare snapnav_results)
add_executable(bench-compare bench/bench_compare.cpp)
target_include_directories(bench-compare PRIVATE bench)
target_link_libraries(bench-compare PRIVATE snapnav_slam_compare snapnav_results)
