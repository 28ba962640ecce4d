// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal import` end to end: every recording in ../shared/data imports with the expected
// counts, angles and ranges (checked against the source files parsed here independently, and
// opened with PCL's own reader); bad inputs exit with 2, name the file and the line or topic,
// leave no partial output and leave the input unchanged.

#include <cmath>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <zlib.h>

#include "common/pose2.hpp"
#include "io/import_rosbag.hpp"
#include "io/import_test_util.hpp"
#include "io/sequence.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

namespace fs = std::filesystem;
using test::runCli;
using test::TempDir;

/// Line `k` (0-based) among the lines of a (possibly gzip) text file starting with `prefix`, read
/// with zlib.
std::string nthLine(const fs::path& file, const std::string& prefix, std::size_t k) {
  gzFile f = gzopen(file.c_str(), "rb");
  std::string line;
  std::vector<char> buf(1 << 20);
  std::size_t seen = 0;
  while (gzgets(f, buf.data(), static_cast<int>(buf.size()))) {
    line = buf.data();
    if (line.compare(0, prefix.size(), prefix) == 0 && seen++ == k) break;
    line.clear();
  }
  gzclose(f);
  return line;
}

std::vector<double> numbersAfter(const std::string& line, char separator, std::size_t skip_words) {
  std::string text = line;
  if (separator != ' ')
    for (char& c : text)
      if (c == separator) c = ' ';
  std::istringstream in(text);
  std::string word;
  for (std::size_t i = 0; i < skip_words; ++i) in >> word;
  std::vector<double> v;
  for (double x; in >> x;) v.push_back(x);
  return v;
}

std::size_t pcdCount(const fs::path& dir) {
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.path().extension() == ".pcd";
  return n;
}

pcl::PointCloud<pcl::PointXYZ> loadWithPcl(const fs::path& file,
                                           Eigen::Vector4f* origin = nullptr) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  EXPECT_EQ(pcl::io::loadPCDFile(file.string(), cloud), 0) << file;
  if (origin) *origin = cloud.sensor_origin_;
  return cloud;
}

struct CarmenCase {
  const char* name;
  const char* file;
  std::size_t scans, beams;
  double first_deg, step_deg;  // CARMEN's angle convention for the beam count
};

void PrintTo(const CarmenCase& c, std::ostream* os) { *os << c.file; }

class CliImportCarmen : public ::testing::TestWithParam<CarmenCase> {};

TEST_P(CliImportCarmen, CountsAnglesRangesAndPosesMatchTheLog) {
  const CarmenCase c = GetParam();
  const fs::path log = test::sharedData() / "carmen" / c.file;
  if (!fs::exists(log)) GTEST_SKIP() << "shared data absent: " << log;
  TempDir dir;
  const auto r =
      runCli("import -q --from carmen " + log.string() + " --out " + (dir / "seq").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(pcdCount(dir / "seq"), c.scans);
  const io::SequenceMeta meta = io::readSequenceMeta(dir / "seq/sequence.json");
  EXPECT_EQ(*meta.beams, static_cast<int>(c.beams));
  EXPECT_DOUBLE_EQ(*meta.range_max_m, 80.0);
  for (std::size_t k : {std::size_t{0}, c.scans / 2, c.scans - 1}) {
    SCOPED_TRACE(k);
    // n r1..rn x y th ox oy oth ts
    const std::vector<double> v = numbersAfter(nthLine(log, "FLASER ", k), ' ', 1);
    ASSERT_EQ(v.size(), c.beams + 8);  // the hostname stopped the stream
    ASSERT_EQ(v[0], static_cast<double>(c.beams));
    Eigen::Vector4f origin;
    const auto cloud = loadWithPcl(dir / "seq" / io::scanFileName(k), &origin);
    ASSERT_EQ(cloud.size(), c.beams);
    for (std::size_t i = 0; i < c.beams; i += 7) {
      const double r_src = v[1 + i];
      if (r_src >= 80.0) {
        EXPECT_TRUE(std::isnan(cloud[i].x)) << i;
        continue;
      }
      EXPECT_NEAR(test::rangeOf(cloud[i].x, cloud[i].y), r_src, 1e-5 * r_src + 1e-6) << i;
      EXPECT_NEAR(test::bearingOf(cloud[i].x, cloud[i].y),
                  deg2rad(c.first_deg + c.step_deg * static_cast<double>(i)), 1e-5)
          << i;
    }
    // 6 significant digits
    EXPECT_NEAR(origin[0], v[1 + c.beams], 1e-3 + 1e-5 * std::abs(v[1 + c.beams]));
    EXPECT_NEAR(origin[1], v[2 + c.beams], 1e-3 + 1e-5 * std::abs(v[2 + c.beams]));
  }
}

INSTANTIATE_TEST_SUITE_P(
    SharedData, CliImportCarmen,
    ::testing::Values(
        CarmenCase{"Intel", "intel-corrected.log.gz", 910, 180, -89.5, 1.0},
        CarmenCase{"MitCsail", "csail-corrected.log.gz", 406, 361, -90.0, 0.5},
        CarmenCase{"Freiburg079", "freiburg-079-corrected.log.gz", 4791, 360, -89.75, 0.5},
        CarmenCase{"FreiburgCampus", "freiburg-campus-corrected.log.gz", 2008, 360, -89.75, 0.5}),
    [](const auto& p) { return std::string(p.param.name); });

TEST(CliImportYdlidar, EveryFileImportsWithOneScanPerLineAndItsBeamCount) {
  const fs::path folder = test::sharedData() / "ydlidar_x4";
  if (!fs::exists(folder)) GTEST_SKIP() << "shared data absent: " << folder;
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(folder)) {
    if (e.path().extension() != ".dat") continue;
    ++files;
    SCOPED_TRACE(e.path().string());
    TempDir dir;
    const auto r = runCli("import -q --from ydlidar " + e.path().string() + " --out " +
                          (dir / "seq").string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::size_t lines = 0;
    {
      std::ifstream in(e.path());
      for (std::string l; std::getline(in, l);) lines += !l.empty();
    }
    ASSERT_EQ(pcdCount(dir / "seq"), lines);
    for (std::size_t k : {std::size_t{0}, lines / 3, lines - 1}) {
      const std::vector<double> v = numbersAfter(nthLine(e.path(), "", k), ',', 0);
      const std::size_t n = v.size() - 3;
      const auto cloud = loadWithPcl(dir / "seq" / io::scanFileName(k));
      ASSERT_EQ(cloud.size(), n);
      for (std::size_t i = 0; i < n; ++i) {
        const double r_src = v[3 + i];
        if (!(r_src >= 0.12 && r_src <= 10.0)) {
          EXPECT_TRUE(std::isnan(cloud[i].x)) << i;
          continue;
        }
        EXPECT_NEAR(test::rangeOf(cloud[i].x, cloud[i].y), r_src, 1e-5 * r_src) << i;
        EXPECT_NEAR(test::angleDiff(test::bearingOf(cloud[i].x, cloud[i].y),
                                    2 * kPi * static_cast<double>(i) / static_cast<double>(n)),
                    0.0, 1e-5)
            << i;
      }
    }
    const io::Sequence seq = io::openSequence(dir / "seq");
    EXPECT_DOUBLE_EQ(seq.scans[0].viewpoint.x_m, 0.0);  // the recording starts at the origin
    EXPECT_DOUBLE_EQ(*seq.meta.range_min_m, 0.12);
  }
  EXPECT_EQ(files, 4u);
}

TEST(CliImportRosbag, RplidarBagGives1319ScansOf360BeamsAtOneStop) {
  const fs::path bag = test::sharedData() / "rplidar_a2_room/rplidar_1.bag";
  if (!fs::exists(bag)) GTEST_SKIP() << "shared data absent: " << bag;
  if (!io::rosbagSupported()) GTEST_SKIP() << "built without ROS1 bag support";
  TempDir dir;
  const auto r = runCli("import -q --from rosbag1 " + bag.string() +
                        " --topic /scan_rplidar --out " + (dir / "seq").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const io::Sequence seq = io::openSequence(dir / "seq");
  ASSERT_EQ(seq.scans.size(), 1319u);
  EXPECT_EQ(seq.stops.size(), 1u);  // static recording: the same VIEWPOINT for every scan
  EXPECT_EQ(*seq.meta.beams, 360);
  EXPECT_DOUBLE_EQ(*seq.meta.range_min_m, 0.15);
  EXPECT_DOUBLE_EQ(*seq.meta.range_max_m, 12.0);
  for (std::size_t k : {0u, 700u, 1318u}) {
    EXPECT_EQ(seq.scans[k].points, 360u);
    EXPECT_TRUE(seq.scans[k].has_intensity);
    const auto cloud = loadWithPcl(seq.scans[k].path);
    std::size_t returns = 0;
    for (const auto& p : cloud) {
      if (std::isnan(p.x)) continue;
      ++returns;
      const double range = test::rangeOf(p.x, p.y);
      EXPECT_GE(range, 0.15 - 1e-6);
      EXPECT_LE(range, 12.0 + 1e-6);
    }
    EXPECT_GT(returns, 300u);
  }
  const auto list = runCli("import --from rosbag1 " + bag.string() + " --list-topics");
  EXPECT_EQ(list.exit_code, 0);
  EXPECT_NE(list.out.find("| /scan_rplidar | sensor_msgs/LaserScan | 1319 |"), std::string::npos)
      << list.out;
  // --every / --max-scans
  const auto some = runCli("import -q --from rosbag1 " + bag.string() +
                           " --every 10 --max-scans 50 --out " + (dir / "some").string());
  ASSERT_EQ(some.exit_code, 0) << some.err;
  EXPECT_EQ(pcdCount(dir / "some"), 50u);
  EXPECT_EQ(test::readFile(dir / "some/scan_000001.pcd"),
            test::readFile(dir / "seq/scan_000010.pcd"));
}

TEST(CliImportRosbag, WithoutRosSupportTheErrorSaysHowToEnableIt) {
  if (io::rosbagSupported()) GTEST_SKIP() << "this build reads bags";
  TempDir dir;
  test::writeFile(dir / "a.bag", "#ROSBAG V2.0\n");
  const auto r = runCli("import --from rosbag1 " + (dir / "a.bag").string() + " --out " +
                        (dir / "seq").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("built without ROS1 bag support"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("-DLIDARCAL_WITH_ROSBAG=ON"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "seq"));
}

// ---- bad inputs: exit 2, a message naming file and line/topic with a remedy, nothing left behind.

struct BadImport {
  fs::path input_dir;               // snapshotted before and after
  std::string args;                 // the whole command line after `import`
  std::vector<std::string> expect;  // parts of the message
};

void expectCleanFailure(const TempDir& dir, const BadImport& b) {
  const auto before = test::snapshot(b.input_dir);
  const auto r = runCli("import " + b.args + " --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  for (const auto& part : b.expect)
    EXPECT_NE(r.err.find(part), std::string::npos) << r.err << "\nmissing: " << part;
  EXPECT_NE(r.err.find(" ("), std::string::npos) << "no remedy: " << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_NE(e.path().filename().string().front(), '.') << "left behind: " << e.path();
  EXPECT_TRUE(test::snapshot(b.input_dir) == before) << "input changed";
}

std::string flaserLine(int n, double r) {
  std::ostringstream o;
  o << "FLASER " << n;
  for (int i = 0; i < n; ++i) o << ' ' << r;
  o << " 0 0 0 0 0 0 1.5 host 1.5\n";
  return o.str();
}

TEST(CliImportBadInput, CarmenLineWithAWrongCount) {
  TempDir dir;
  fs::create_directories(dir / "in");
  std::string log = "# log\n";
  for (int k = 0; k < 30; ++k) log += flaserLine(181, 2.0);
  log += "FLASER 181 1 2 3 0 0 0 0 0 0 1.5 host 1.5\n";  // line 32: 3 ranges instead of 181
  for (int k = 0; k < 5; ++k) log += flaserLine(181, 2.0);
  test::writeGzip(dir / "in/bad.log.gz", log);
  expectCleanFailure(dir, {dir / "in",
                           "--from carmen " + (dir / "in/bad.log.gz").string(),
                           {"bad.log.gz", "line 32 (FLASER)", "expected 191"}});
}

TEST(CliImportBadInput, CorruptedGzip) {
  TempDir dir;
  fs::create_directories(dir / "in");
  std::string log;
  for (int k = 0; k < 2000; ++k) log += flaserLine(181, 1.0 + 0.001 * k);
  test::writeGzip(dir / "good.log.gz", log);
  std::string gz = test::readFile(dir / "good.log.gz");
  fs::remove(dir / "good.log.gz");
  test::writeFile(dir / "in/cut.log.gz", gz.substr(0, gz.size() * 2 / 3));
  expectCleanFailure(dir, {dir / "in",
                           "--from carmen " + (dir / "in/cut.log.gz").string(),
                           {"cut.log.gz", "after line", "gzip data is damaged or cut short"}});
  for (std::size_t i = gz.size() / 2; i < gz.size() / 2 + 16; ++i)
    gz[i] = static_cast<char>(gz[i] ^ 0x5a);
  fs::remove(dir / "in/cut.log.gz");
  test::writeFile(dir / "in/flipped.log.gz", gz);
  expectCleanFailure(dir, {dir / "in",
                           "--from carmen " + (dir / "in/flipped.log.gz").string(),
                           {"flipped.log.gz", "line"}});
}

TEST(CliImportBadInput, TruncatedBagAndMissingTopic) {
  const fs::path bag = test::sharedData() / "rplidar_a2_room/rplidar_1.bag";
  if (!fs::exists(bag)) GTEST_SKIP() << "shared data absent: " << bag;
  if (!io::rosbagSupported()) GTEST_SKIP() << "built without ROS1 bag support";
  TempDir dir;
  fs::create_directories(dir / "in");
  test::writeFile(dir / "in/cut.bag", test::readFile(bag).substr(0, 1500000));
  expectCleanFailure(dir, {dir / "in",
                           "--from rosbag1 " + (dir / "in/cut.bag").string(),
                           {"cut.bag", "rosbag reindex"}});
  expectCleanFailure(dir, {bag.parent_path(),
                           "--from rosbag1 " + bag.string() + " --topic /scan",
                           {"rplidar_1.bag", "--topic /scan", "no such topic", "/scan_rplidar"}});
}

TEST(CliImportBadInput, OptionsThatDoNotApplyAndOutputInsideTheInput) {
  TempDir dir;
  fs::create_directories(dir / "in");
  test::writeFile(dir / "in/a.csv", "scan,x_m,y_m,yaw_rad,angle_rad,range_m\n0,0,0,0,0,1\n");
  expectCleanFailure(
      dir,
      {dir / "in", "--from csv " + (dir / "in/a.csv").string() + " --topic /scan", {"--topic"}});
  expectCleanFailure(
      dir,
      {dir / "in", "--from csv " + (dir / "in/a.csv").string() + " --pose odometry", {"--pose"}});
  const auto r = runCli("import --from csv " + (dir / "in/a.csv").string() + " --out " +
                        (dir / "in/a.csv").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(test::readFile(dir / "in/a.csv"),
            "scan,x_m,y_m,yaw_rad,angle_rad,range_m\n0,0,0,0,0,1\n");
}

TEST(CliImport, CsvRoundTripThroughTheCommand) {
  TempDir dir;
  test::writeFile(dir / "a.csv",
                  "scan,x_m,y_m,yaw_rad,angle_rad,range_m,intensity\n"
                  "0,0.5,0.25,0.1,0.0,2.0,7\n0,0.5,0.25,0.1,1.5707963267948966,,8\n"
                  "1,0.75,0.25,0.1,0.0,3.0,9\n1,0.75,0.25,0.1,1.5707963267948966,1.0,10\n");
  const auto r =
      runCli("import --from csv " + (dir / "a.csv").string() +
             " --range-max 2.5 --sensor-name 'my lidar' --out " + (dir / "seq").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("imported 2 of 2 scans"), std::string::npos) << r.out;
  const io::Sequence seq = io::openSequence(dir / "seq");
  ASSERT_EQ(seq.scans.size(), 2u);
  EXPECT_EQ(seq.stops.size(), 2u);
  EXPECT_EQ(*seq.meta.sensor_name, "my lidar");
  EXPECT_DOUBLE_EQ(*seq.meta.range_max_m, 2.5);
  const io::Scan s1 = io::readScan(seq.scans[1].path);
  EXPECT_TRUE(std::isnan((*s1.cloud)[0].x));  // 3.0 m > --range-max 2.5
  EXPECT_NEAR((*s1.cloud)[1].y, 1.0, 1e-6);
  EXPECT_EQ((*s1.cloud)[1].intensity, 10.0f);
  EXPECT_NEAR(seq.scans[1].viewpoint.x_m, 0.75, 1e-6);
}

}  // namespace
}  // namespace lidarcal
