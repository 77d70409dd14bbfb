// eval-slam: dead reckoning and laser SLAM (thesis 5.3) over an LCM log against a reference, MRPT's
// icp-slam beside it, the suite of real logs (eval_slam_app.hpp).
#include "eval_app.hpp"
#include "eval_slam_app.hpp"

int main(int argc, char** argv) { return snapnav::eval::RunApp<snapnav::eval::EvalSlamApp>(argc, argv); }
