# Place-cell localization evaluation (./snapnav eval localization; thesis 5.1.4, 5.2.2, fig. 5.9).
# Included by tools/CMakeLists.txt: paths are relative to tools/.
add_library(snapnav_localization_eval STATIC eval/localization_eval.cpp eval/leave_one_out.cpp eval/exploration.cpp)
target_include_directories(snapnav_localization_eval PUBLIC eval)
target_link_libraries(snapnav_localization_eval PUBLIC snapnav_homing_eval snapnav_places snapnav_plot
  PRIVATE snapnav_results opencv_imgproc)
add_executable(eval-localization eval/eval_localization_main.cpp)
target_link_libraries(eval-localization PRIVATE snapnav_localization_eval snapnav_sim_node snapnav_glue_places snapnav_results)
