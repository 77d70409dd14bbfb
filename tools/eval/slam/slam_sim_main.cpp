// slam-sim-eval: dead reckoning and laser SLAM on a simulated route with ground truth (slam_sim_app.hpp).
#include "eval_app.hpp"
#include "slam_sim_app.hpp"

int main(int argc, char** argv) { return snapnav::eval::RunApp<snapnav::eval::SlamSimEvalApp>(argc, argv); }
