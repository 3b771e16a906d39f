// One libFuzzer program per entry of targets.h: RTHS_FUZZ_ENTRY names it (set by CMakeLists.txt).
#include <spdlog/spdlog.h>

#include "fuzz/targets.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spdlog::set_level(
      spdlog::level::off);  // nodes log every rejected message; the fuzzer needs speed
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return rths::fuzz::RTHS_FUZZ_ENTRY(data, size);
}
