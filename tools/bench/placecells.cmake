# bench-placecells (./snapnav bench placecells): one localization query against memories of 100,
# 1,000 and 10,000 place cells on one core, beside the exhaustive comparison. Included by
# tools/CMakeLists.txt: paths are relative to tools/.
add_executable(bench-placecells bench/bench_placecells.cpp)
target_link_libraries(bench-placecells PRIVATE snapnav_homing_eval snapnav_places snapnav_glue_places snapnav_sim_node
  snapnav_results)
