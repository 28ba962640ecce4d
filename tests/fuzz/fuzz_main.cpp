// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer entry point of one target, chosen at compile time (LIDARCAL_FUZZ_TARGET, see
// tests/fuzz/CMakeLists.txt): fuzz_pcd, fuzz_json, ...

#include <cstdlib>
#include <cstring>

#include <pcl/console/print.h>

#include "fuzz_inputs.hpp"

namespace {
lidarcal::fuzz::Target find() {
  for (const auto& t : lidarcal::fuzz::targets())
    if (std::strcmp(t.name, LIDARCAL_FUZZ_TARGET) == 0) return t.run;
  std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // as the lidarcal command does
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const lidarcal::fuzz::Target run = find();
  run(data, size);
  return 0;
}
