// libFuzzer target (SNAPNAV_LIBFUZZER=ON, clang): the first byte picks an lcm type, the rest is
// its payload. A payload that decodes must encode back to the same bytes; libFuzzer's
// -malloc_limit_mb catches a decode that allocates beyond a bound. Run: tools/libfuzzer.sh.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_samples.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const auto* types = new std::vector<snapnav::fuzz::TypeCase>(snapnav::fuzz::AllTypes());
  if (size < 1) return 0;
  const auto& t = (*types)[data[0] % types->size()];
  const std::string bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  std::string error;
  const auto again = t.decode(bytes, &error);
  if (again && *again != bytes) {
    std::fprintf(stderr, "%s: decoded, but encodes to other bytes\n", t.name.c_str());
    std::abort();
  }
  if (!again && error.empty()) {
    std::fprintf(stderr, "%s: rejected without a reason\n", t.name.c_str());
    std::abort();
  }
  return 0;
}
