#include "snapnav/glue/app.hpp"

#include <iostream>
#include <string>

#include "snapnav/glue/flags.hpp"

namespace snapnav::glue {

int RunMain(int argc, char** argv, const std::function<int(int, char**)>& app) {
  std::string program = argc > 0 ? argv[0] : "snapnav";
  if (const auto slash = program.rfind('/'); slash != std::string::npos) program = program.substr(slash + 1);
  try {
    return app(argc, argv);
  } catch (const FlagError& e) {
    std::cerr << program << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace snapnav::glue
