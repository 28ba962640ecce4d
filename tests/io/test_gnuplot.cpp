// SPDX-License-Identifier: BSD-3-Clause
// Running gnuplot (io/gnuplot.hpp): a failure is reported by gnuplot's own message, not by a path
// that may be a staging directory gone by the time the user reads it.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "io/gnuplot.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

TEST(Gnuplot, AFailingScriptIsReportedByItsNameAndGnuplotsLastMessage) {
  if (!io::gnuplotInstalled()) GTEST_SKIP() << "gnuplot is not installed";
  test::TempDir dir;
  // No valid point: gnuplot warns about the file, then stops on the empty range.
  test::writeFile(dir / "empty.dat", "# nothing\n");
  test::writeFile(dir / "bad.gp",
                  "set terminal pngcairo\nset output \"bad.png\"\nplot \"empty.dat\" using 1:2\n");
  std::string why;
  EXPECT_FALSE(io::runGnuplot(dir.path(), "bad.gp", &why));
  EXPECT_NE(why.find("gnuplot failed on bad.gp: "), std::string::npos) << why;
  EXPECT_NE(why.find("range is invalid"), std::string::npos) << why;
  EXPECT_EQ(why.find(dir.path().string()), std::string::npos) << why;
}

TEST(Gnuplot, AWorkingScriptDrawsAndLeavesNoLog) {
  if (!io::gnuplotInstalled()) GTEST_SKIP() << "gnuplot is not installed";
  test::TempDir dir;
  test::writeFile(dir / "good.gp", "set terminal pngcairo\nset output \"good.png\"\nplot x\n");
  std::string why;
  EXPECT_TRUE(io::runGnuplot(dir.path(), "good.gp", &why)) << why;
  EXPECT_TRUE(std::filesystem::exists(dir / "good.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "gnuplot.log"));
}

}  // namespace
}  // namespace lidarcal
