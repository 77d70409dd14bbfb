// eval-localization: place-cell localization evaluated the way the thesis does (thesis 5.1.4, 5.2.2,
// fig. 5.9; eval_localization_app.hpp).
#include "eval_app.hpp"
#include "eval_localization_app.hpp"

int main(int argc, char** argv) { return snapnav::eval::RunApp<snapnav::eval::EvalLocalizationApp>(argc, argv); }
