// eval-compare: dead reckoning, laser SLAM, RatSLAM and fused SLAM on the same simulated runs with
// ground truth, and the laser methods on recorded logs (issue 8; eval_compare_app.hpp).
#include "eval_app.hpp"
#include "eval_compare_app.hpp"

int main(int argc, char** argv) { return snapnav::eval::RunApp<snapnav::eval::EvalCompareApp>(argc, argv); }
