// SPDX-License-Identifier: BSD-3-Clause
// Replays every fuzz target's seed corpus (tests/fuzz/corpus/<target>/) and every input a fuzz
// run ever found a problem with (tests/fuzz/regressions/<target>/, committed with the fix) in
// the normal build, and under the sanitizers in scripts/test-sanitizers.sh: each must give a
// result or a clean InputError.

#include <gtest/gtest.h>

#include "fuzz_inputs.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

namespace fs = std::filesystem;

class FuzzRegressions : public ::testing::TestWithParam<fuzz::NamedTarget> {};

TEST_P(FuzzRegressions, EveryCorpusAndRegressionInputIsReadOrRefusedCleanly) {
  const auto& t = GetParam();
  std::size_t inputs = 0;
  for (const char* kind : {"corpus", "regressions"}) {
    const fs::path dir = test::sourceDir() / "tests/fuzz" / kind / t.name;
    if (!fs::is_directory(dir)) continue;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file()) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      SCOPED_TRACE(f.string());
      const std::string bytes = test::readFile(f);
      EXPECT_NO_THROW(t.run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
      ++inputs;
    }
  }
  EXPECT_GT(inputs, 0u) << "no seed corpus for " << t.name;
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzRegressions, ::testing::ValuesIn(fuzz::targets()),
                         [](const ::testing::TestParamInfo<fuzz::NamedTarget>& p) {
                           return std::string(p.param.name);
                         });

}  // namespace
}  // namespace lidarcal
