// SPDX-License-Identifier: BSD-3-Clause
// A recording's format told from its content (io/detect_format.hpp): small inputs of every
// kind, gzip or not, the shared recordings, and `import` without --from giving what --from gives.

#include <string>

#include <gtest/gtest.h>
#include <zlib.h>

#include "common/errors.hpp"
#include "io/detect_format.hpp"
#include "io/sequence.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

namespace fs = std::filesystem;
using namespace std::string_literals;
using test::runCli;
using test::TempDir;
using test::writeFile;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(ImportFormat, DetectedFromTheContentOfSmallInputs) {
  TempDir dir;
  auto gzip = [](const fs::path& file, const std::string& text) {
    gzFile f = gzopen(file.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    gzwrite(f, text.data(), static_cast<unsigned>(text.size()));
    gzclose(f);
  };
  const std::string carmen =
      "# CARMEN Logfile\n# message formats defined: PARAM ODOM FLASER\n"
      "PARAM robot_frontlaser_offset 0.0 nohost 0\n"
      "FLASER 3 1.0 1.1 1.2 0 0 0 0 0 0 1.0 host 1.0\n";
  const std::string ydlidar =
      "0.0, 0.0, 0.1, 1.0, 1.1, 0.0, 1.3\n10.0, 1.0, 0.13, 1.0, 1.1, 1.2, 1.3\n";
  const std::string csv =
      "scan,x_m,y_m,yaw_rad,angle_rad,range_m\n0,0,0,0,0,1.0\n0,0,0,0,1.5,2.0\n";
  // Names that say nothing: only the content decides.
  writeFile(dir / "a", carmen);
  gzip(dir / "b", carmen);
  writeFile(dir / "c", ydlidar);
  gzip(dir / "d", ydlidar);
  writeFile(dir / "e", csv);
  writeFile(dir / "f", "#ROSBAG V2.0\nE\0\0\0"s);
  writeFile(dir / "g", std::string("\x89MCAP0\r\n", 8) + "rest");
  writeFile(dir / "h", "hello world\n");
  writeFile(dir / "i", std::string("\x01\x02\x03\x00\x05", 5));
  using io::RecordingKind;
  const std::vector<std::pair<const char*, RecordingKind>> cases = {
      {"a", RecordingKind::carmen},  {"b", RecordingKind::carmen},  {"c", RecordingKind::ydlidar},
      {"d", RecordingKind::ydlidar}, {"e", RecordingKind::csv},     {"f", RecordingKind::rosbag1},
      {"g", RecordingKind::mcap},    {"h", RecordingKind::unknown}, {"i", RecordingKind::unknown}};
  for (const auto& [name, kind] : cases) {
    SCOPED_TRACE(name);
    const auto d = io::detectRecordingFormat(dir / name);
    EXPECT_EQ(io::toString(d.kind), std::string(io::toString(kind))) << d.evidence;
    EXPECT_EQ(d.gzip, std::string(name) == "b" || std::string(name) == "d");
  }
  EXPECT_THROW(io::detectRecordingFormat(dir / "missing"), InputError);
  EXPECT_THROW(io::detectRecordingFormat(dir.path()), InputError);
}

TEST(ImportFormat, TheSharedRecordingsAreRecognised) {
  const fs::path data = test::sharedData();
  if (!fs::exists(data / "carmen")) GTEST_SKIP() << "shared data absent: " << data;
  EXPECT_EQ(io::detectRecordingFormat(data / "carmen/intel-corrected.log.gz").kind,
            io::RecordingKind::carmen);
  EXPECT_EQ(io::detectRecordingFormat(data / "rplidar_a2_room/rplidar_1.bag").kind,
            io::RecordingKind::rosbag1);
  for (const auto& e : fs::directory_iterator(data / "ydlidar_x4")) {
    SCOPED_TRACE(e.path().string());
    EXPECT_EQ(io::detectRecordingFormat(e.path()).kind, io::RecordingKind::ydlidar);
  }
  EXPECT_EQ(io::detectRecordingFormat(data / "pcl/table_scene_mug_stereo_textured.pcd").kind,
            io::RecordingKind::unknown);
}

TEST(ImportFormat, ImportWithoutFromGivesWhatFromGives) {
  TempDir dir;
  std::ostringstream log;
  for (int k = 0; k < 3; ++k) {
    log << "FLASER 5";
    for (int i = 0; i < 5; ++i) log << ' ' << 1.0 + 0.1 * i;
    log << ' ' << 0.3 * k << " 0 0 " << 0.3 * k << " 0 0 " << k << " host " << k << '\n';
  }
  writeFile(dir / "rec.log", log.str());
  const auto detected =
      runCli("import " + (dir / "rec.log").string() + " -o " + (dir / "s1").string());
  ASSERT_EQ(detected.exit_code, 0) << detected.err;
  EXPECT_TRUE(contains(detected.err, "as carmen (from its content; --from overrides)"))
      << detected.err;
  const auto named = runCli("import -q --from carmen " + (dir / "rec.log").string() + " -o " +
                            (dir / "s2").string());
  ASSERT_EQ(named.exit_code, 0) << named.err;
  EXPECT_TRUE(test::snapshot(dir / "s1") == test::snapshot(dir / "s2"));
  EXPECT_EQ(io::openSequence(dir / "s1").scans.size(), 3u);
  // --from still overrides: the log read as CSV fails on the CSV header.
  const auto forced =
      runCli("import -q --from csv " + (dir / "rec.log").string() + " -o " + (dir / "s3").string());
  EXPECT_EQ(forced.exit_code, 2);
  // A damaged MCAP file (read as a ROS 2 bag) and unknown content: exit 2 with what to do.
  writeFile(dir / "rec.mcap", std::string("\x89MCAP0\r\n", 8) + "rest");
  const auto mcap =
      runCli("import " + (dir / "rec.mcap").string() + " -o " + (dir / "s4").string());
  EXPECT_EQ(mcap.exit_code, 2);
  EXPECT_TRUE(contains(mcap.err, "as rosbag2")) << mcap.err;
  EXPECT_TRUE(contains(mcap.err, "without a Footer")) << mcap.err;
  EXPECT_TRUE(contains(mcap.err, "mcap recover")) << mcap.err;
  writeFile(dir / "notes.txt", "hello\n");
  const auto unknown =
      runCli("import " + (dir / "notes.txt").string() + " -o " + (dir / "s5").string());
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_TRUE(contains(unknown.err, "cannot tell the recording's format")) << unknown.err;
  EXPECT_TRUE(contains(unknown.err, "--from")) << unknown.err;
  EXPECT_FALSE(fs::exists(dir / "s4"));
  EXPECT_FALSE(fs::exists(dir / "s5"));
}

}  // namespace
}  // namespace lidarcal
