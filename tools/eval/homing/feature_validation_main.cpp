// eval-features: our SURF against OpenCV's SIFT under known transforms (feature_validation.hpp).
#include "eval_app.hpp"
#include "feature_validation.hpp"

int main(int argc, char** argv) { return snapnav::eval::RunApp<snapnav::eval::EvalFeaturesApp>(argc, argv); }
