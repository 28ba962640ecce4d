// SPDX-License-Identifier: BSD-3-Clause
// End-to-end checks of `lidarcal detect`: labelled copies of the scans, landmarks.csv,
// untouched input, atomic and deterministic output, refusals, a sequence without landmarks.

#include <cmath>
#include <cstring>
#include <map>
#include <regex>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "io/landmarks_csv.hpp"
#include "io/pcd_scan.hpp"
#include "io/scene_io.hpp"
#include "io/sequence.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;
namespace fs = std::filesystem;

std::string scene(const char* name) { return (test::sourceDir() / "data/scenes" / name).string(); }

bool sameFloat(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// One stop: the association cannot follow a pole over stops; the summary says what a discard
// means there (not "at too few stops") and what the recording cannot do, each count with its noun.
TEST(CliDetect, AOneStopRecordingIsDescribedAsOne) {
  TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(runCli("simulate -q --scene " + scene("paper_field.json") + " --out " + sim +
                   " --seed 3 --stops 1 --scans-per-stop 4")
                .exit_code,
            0);
  const auto r = runCli("detect -q " + sim + "/scans --out " + (dir / "det").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("4 scans at 1 stop\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("found in fewer than half the scans of the stop"), std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("too few stops"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("this recording has 1 stop,"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("calibrate --reference"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("(s)"), std::string::npos) << r.out;
}

TEST(CliDetect, LabelsEveryScanAndWritesTheLandmarkTable) {
  TempDir dir;
  const std::string sim = (dir / "sim").string(), out = (dir / "det").string();
  ASSERT_EQ(runCli("simulate -q --scene " + scene("paper_field.json") + " --out " + sim +
                   " --seed 3 --stops 4 --scans-per-stop 3")
                .exit_code,
            0);
  const auto before = test::snapshot(sim);
  const auto r =
      runCli("detect -q " + sim + "/scans --out " + out + " --truth " + sim + "/truth.json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("5 landmarks"), std::string::npos) << r.out;
  // The evaluation row: every detection a true positive, no false positive, precision 1.
  EXPECT_TRUE(std::regex_search(r.out, std::regex(R"(\| (\d+) \| \1 \| 0 \| 1\.0000 \|)")))
      << r.out;
  EXPECT_TRUE(test::snapshot(sim) == before);  // the input is untouched

  // Same points in the same order (NaN kept), plus a label; the table agrees with the labels.
  const io::Sequence in = io::openSequence(sim + "/scans"), labelled = io::openSequence(out);
  ASSERT_EQ(labelled.scans.size(), in.scans.size());
  EXPECT_TRUE(fs::exists(fs::path(out) / "sequence.json"));
  const auto rows = io::readLandmarksCsv(fs::path(out) / "landmarks.csv");
  std::map<std::pair<std::string, int>, std::size_t> points_of;  // (file, id) -> n_points
  for (const auto& row : rows) {
    EXPECT_TRUE(points_of.emplace(std::make_pair(row.file, row.landmark), row.n_points).second)
        << "one row per id per scan";
    EXPECT_NEAR(row.range_m, std::hypot(row.centre_x_m, row.centre_y_m), 1e-6);
    EXPECT_NEAR(row.bearing_rad, std::atan2(row.centre_y_m, row.centre_x_m), 1e-6);
    EXPECT_DOUBLE_EQ(row.radius_m, 0.12);
  }
  std::set<int> ids;
  for (std::size_t i = 0; i < in.scans.size(); ++i) {
    const io::Scan a = io::readScan(in.scans[i].path), b = io::readScan(labelled.scans[i].path);
    EXPECT_EQ(in.scans[i].name(), labelled.scans[i].name());
    ASSERT_EQ(a.cloud->size(), b.cloud->size());
    ASSERT_EQ(b.labels.size(), b.cloud->size());
    EXPECT_NEAR(b.viewpoint.x_m, a.viewpoint.x_m, 1e-9);
    std::map<int, std::size_t> count;
    for (std::size_t k = 0; k < a.cloud->size(); ++k) {
      EXPECT_TRUE(sameFloat((*a.cloud)[k].x, (*b.cloud)[k].x) &&
                  sameFloat((*a.cloud)[k].y, (*b.cloud)[k].y));
      if (b.labels[k] != 0) {
        EXPECT_TRUE(std::isfinite((*b.cloud)[k].x));
        ++count[static_cast<int>(b.labels[k])];
        ids.insert(static_cast<int>(b.labels[k]));
      }
    }
    const std::string name = in.scans[i].name();
    for (const auto& [id, n] : count)
      EXPECT_EQ(points_of[std::make_pair(name, id)], n) << name << " id " << id;
  }
  EXPECT_EQ(ids, (std::set<int>{1, 2, 3, 4, 5}));
}

TEST(CliDetect, SameInputGivesTheSameBytesAndOverwriteIsExplicit) {
  TempDir dir;
  const std::string seq = (test::sourceDir() / "data/example/scans").string();
  ASSERT_EQ(runCli("detect -q " + seq + " --out " + (dir / "a").string()).exit_code, 0);
  ASSERT_EQ(runCli("detect -q " + seq + " --out " + (dir / "b").string()).exit_code, 0);
  EXPECT_TRUE(test::snapshot(dir / "a") == test::snapshot(dir / "b"));
  const auto again = runCli("detect -q " + seq + " --out " + (dir / "a").string());
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_NE(again.err.find("overwrite"), std::string::npos) << again.err;
  EXPECT_EQ(
      runCli("detect -q " + seq + " --out " + (dir / "a").string() + " --overwrite").exit_code, 0);
}

TEST(CliDetect, RefusesAnOutputInsideTheInput) {
  TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(runCli("simulate -q --scene " + scene("paper_field.json") + " --out " + sim +
                   " --stops 1 --scans-per-stop 1")
                .exit_code,
            0);
  const auto before = test::snapshot(sim);
  const auto r = runCli("detect -q " + sim + "/scans --out " + sim + "/scans/labelled");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(r.err.empty());
  EXPECT_TRUE(test::snapshot(sim) == before);
}

TEST(CliDetect, SequenceWithoutLandmarksOrMetadataGivesZeroLandmarks) {
  TempDir dir;
  // Walls only, and no sequence.json: nothing round to find.
  Scene s = io::readScene(scene("paper_field.json"));
  s.landmarks.clear();
  test::writeFile(dir / "walls.json", io::sceneToJson(s).dump());
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(runCli("simulate -q --scene " + (dir / "walls.json").string() + " --out " + sim +
                   " --stops 3 --scans-per-stop 2")
                .exit_code,
            0);
  fs::remove(fs::path(sim) / "scans/sequence.json");
  const auto r = runCli("detect -q " + sim + "/scans --out " + (dir / "det").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("zero landmarks"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "det/sequence.json"));
  EXPECT_TRUE(io::readLandmarksCsv(dir / "det/landmarks.csv").empty());
  const io::Scan first = io::readScan(dir / "det/scan_000000.pcd");
  for (auto l : first.labels) EXPECT_EQ(l, 0u);
}

TEST(CliDetect, BadOptionsAreRefused) {
  TempDir dir;
  const std::string seq = (test::sourceDir() / "data/example/scans").string();
  EXPECT_EQ(runCli("detect " + seq).exit_code, 2);  // --out is required
  EXPECT_EQ(runCli("detect " + seq + " --out " + (dir / "x").string() + " --radius -1").exit_code,
            2);
  EXPECT_EQ(
      runCli("detect " + seq + " --out " + (dir / "x").string() + " --radius 0.1 --estimate-radius")
          .exit_code,
      2);
  EXPECT_EQ(
      runCli("detect " + (dir / "missing").string() + " --out " + (dir / "x").string()).exit_code,
      2);
  EXPECT_FALSE(fs::exists(dir / "x"));
}

}  // namespace
}  // namespace lidarcal
