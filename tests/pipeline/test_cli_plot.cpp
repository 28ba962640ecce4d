// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal plot`: a labelled scan becomes a PNG; bad input is reported.

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;

TEST(CliPlot, DrawsALabelledScanWithItsCircles) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "gnuplot is not installed";
  TempDir dir;
  const std::string scene = (test::sourceDir() / "data/scenes/paper_field.json").string();
  ASSERT_EQ(runCli("simulate -q --scene " + scene + " --out " + (dir / "s").string() +
                   " --stops 4 --scans-per-stop 1")
                .exit_code,
            0);
  ASSERT_EQ(runCli("detect -q " + (dir / "s/scans").string() + " --out " + (dir / "d").string())
                .exit_code,
            0);
  const auto r =
      runCli("plot " + (dir / "d/scan_000000.pcd").string() + " --landmarks " +
             (dir / "d/landmarks.csv").string() + " --out " + (dir / "scan.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string png = test::readFile(dir / "scan.png");
  ASSERT_GT(png.size(), 1000u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  // Nothing else is left beside the picture.
  std::size_t entries = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    entries += e.path().filename().string()[0] == '.';
  EXPECT_EQ(entries, 0u);
}

TEST(CliPlot, MissingScanIsReported) {
  TempDir dir;
  const auto r = runCli("plot /nonexistent/scan.pcd --out " + (dir / "x.png").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

}  // namespace
}  // namespace lidarcal
