// eval-ratslam: RatSLAM on a simulated route with ground truth (eval_ratslam_app.hpp).
#include "eval_app.hpp"
#include "eval_ratslam_app.hpp"

int main(int argc, char** argv) { return snapnav::eval::RunApp<snapnav::eval::EvalRatSlamApp>(argc, argv); }
