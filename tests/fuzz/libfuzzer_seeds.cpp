// Writes the seed corpora of the libFuzzer targets: every sample message, prefixed with the
// byte that selects its type (decoders) or its channel (nodes).
#include <cstdio>
#include <fstream>
#include <string>

#include "fuzz_samples.hpp"
#include "snapnav/glue/codec.hpp"

int main(int argc, char** argv) {
  using namespace snapnav;
  if (argc != 3) {
    std::fprintf(stderr, "usage: libfuzzer-seeds DECODER_CORPUS NODE_CORPUS\n");
    return 2;
  }
  const auto types = fuzz::AllTypes();
  for (size_t i = 0; i < types.size(); ++i) {
    std::ofstream(std::string(argv[1]) + "/" + types[i].name, std::ios::binary)
        << static_cast<char>(i) << types[i].sample;
  }
  const std::string node_seeds[] = {glue::Encode(fuzz::SampleOdometry()), glue::Encode(fuzz::SampleLaserScan()),
                                    glue::Encode(fuzz::SamplePose()), glue::Encode(fuzz::SampleHomingVector()),
                                    glue::Encode(fuzz::SampleRoute())};
  for (int c = 0; c < 5; ++c) {
    std::ofstream(std::string(argv[2]) + "/channel" + std::to_string(c), std::ios::binary)
        << static_cast<char>(c) << node_seeds[c];
  }
  return 0;
}
