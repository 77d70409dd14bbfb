// eval-route: route following in closed loop with place cells, odometry and homing (thesis 5.1.2-5.1.3,
// issue 6; eval_route_app.hpp).
#include "eval_app.hpp"
#include "eval_route_app.hpp"

int main(int argc, char** argv) { return snapnav::eval::RunApp<snapnav::eval::EvalRouteApp>(argc, argv); }
