// eval-homing: snapshot homing evaluated the way the thesis does (3.1.4, Appendix A): angular
// error over a scene's grid database, the AAE, the closed-loop return ratio, vector maps and
// figures (eval_homing_app.hpp).
#include "eval_app.hpp"
#include "eval_homing_app.hpp"

int main(int argc, char** argv) { return snapnav::eval::RunApp<snapnav::eval::EvalHomingApp>(argc, argv); }
