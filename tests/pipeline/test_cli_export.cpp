// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal export`: the ROS parameter YAML carries the model exactly; the lookup table inverts
// the polynomial and equals what `lidarcal correct` gives for the same readings.

#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

#include "io/pcd_scan.hpp"
#include "io/sequence.hpp"
#include "io/sequence_writer.hpp"
#include "ros_test_util.hpp"

namespace lidarcal::test {
namespace {

std::vector<double> yamlList(const std::string& yaml, const std::string& key) {
  const auto at = yaml.find("\n" + key + ": [");
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return {};
  std::istringstream in(yaml.substr(at + key.size() + 4, yaml.find(']', at) - at - key.size() - 4));
  std::vector<double> values;
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(std::strtod(item.c_str(), nullptr));
  return values;
}

std::string yamlValue(const std::string& yaml, const std::string& key) {
  const auto at = yaml.find("\n" + key + ": ");
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return {};
  const auto start = at + key.size() + 3;
  const auto end = yaml.find_first_of(" \n", start);
  return yaml.substr(start, end - start);
}

TEST(Export, YamlCarriesTheModelExactly) {
  TempDir dir;
  const CalibrationModel m = polynomialModel("test sensor", 360);
  io::writeModel(dir / "model.json", m);
  const CliResult r = runCli("export " + (dir / "model.json").string() +
                             " --format yaml --inversion ml -o " + (dir / "model.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string y = readFile(dir / "model.yaml");
  EXPECT_EQ(yamlList(y, "bias_alpha"), m.model.bias.alpha);  // shortest round-trip text: exact
  EXPECT_EQ(yamlList(y, "valid_range_m"), (std::vector<double>{0.5, 8.0}));
  const auto readings = yamlList(y, "valid_reading_m");
  ASSERT_EQ(readings.size(), 2u);
  EXPECT_EQ(readings[0], m.model.bias(0.5));
  EXPECT_EQ(readings[1], m.model.bias(8.0));
  EXPECT_EQ(yamlValue(y, "inversion"), "ml");
  EXPECT_EQ(yamlValue(y, "outside"), "linear");  // the default: continued at the edges' slope
  EXPECT_EQ(yamlValue(y, "beams"), "360");
  EXPECT_NE(y.find("\nsensor_name: \"test sensor\"\n"), std::string::npos) << y;
  // Standard output when no -o is given: the same text.
  const CliResult s =
      runCli("export " + (dir / "model.json").string() + " --format yaml --inversion ml");
  ASSERT_EQ(s.exit_code, 0) << s.err;
  EXPECT_EQ(s.out, y);
}

TEST(Export, LutInvertsThePolynomialOverTheFittedRange) {
  TempDir dir;
  const CalibrationModel m = polynomialModel("test sensor", 0);
  io::writeModel(dir / "model.json", m);
  const CliResult r =
      runCli("export " + (dir / "model.json").string() +
             " --format lut --step 0.01 --outside keep -o " + (dir / "lut.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = readLut(readFile(dir / "lut.csv"));
  const double lo = m.model.bias(0.5), hi = m.model.bias(8.0);
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(std::floor((hi - lo) / 0.01)) + 2);
  EXPECT_EQ(rows.front().first, lo);
  EXPECT_EQ(rows.back().first, hi);
  EXPECT_NEAR(rows.front().second, 0.5, 1e-8);
  EXPECT_NEAR(rows.back().second, 8.0, 1e-8);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    SCOPED_TRACE(i);
    const auto [y, d] = rows[i];
    ASSERT_TRUE(std::isfinite(d));
    EXPECT_NEAR(m.model.bias(d), y, 2e-8);  // LS: f(range) = reading
    if (i > 0) {
      EXPECT_GT(d, rows[i - 1].second);
    }
    if (i > 0 && i + 1 < rows.size()) {
      EXPECT_NEAR(y - rows[i - 1].first, 0.01, 1e-8);
    }
  }
}

struct LutCase {
  const char* inversion;
  const char* outside;
};

class LutEqualsCorrect : public ::testing::TestWithParam<LutCase> {};

// Every LUT reading put into a scan (one beam each), corrected by `lidarcal correct`: the
// corrected point's range is the LUT's range, to the float precision of a PCD coordinate.
TEST_P(LutEqualsCorrect, ForEveryRow) {
  const LutCase c = GetParam();
  TempDir dir;
  const CalibrationModel m = polynomialModel("test sensor", 0);
  io::writeModel(dir / "model.json", m);
  const std::string options =
      std::string(" --inversion ") + c.inversion + " --outside " + c.outside;
  const CliResult r =
      runCli("export " + (dir / "model.json").string() + " --format lut --step 0.05 -o " +
             (dir / "lut.csv").string() + options);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = readLut(readFile(dir / "lut.csv"));
  ASSERT_GT(rows.size(), 100u);
  {
    io::SequenceWriter writer(dir / "seq", {});
    io::RawScan scan;
    scan.range_min_m = m.model.range_min_m;
    scan.range_max_m = m.model.range_max_m;
    for (const auto& [y, d] : rows) {
      scan.angles_rad.push_back(0.001 * static_cast<double>(scan.angles_rad.size()));
      scan.ranges_m.push_back(static_cast<float>(y));
    }
    writer.add(scan);
    writer.commit("test sensor");
  }
  const CliResult corrected =
      runCli("correct " + (dir / "seq").string() + " --model " + (dir / "model.json").string() +
             " -o " + (dir / "out").string() + options);
  ASSERT_EQ(corrected.exit_code, 0) << corrected.err;
  const io::Scan raw = io::readScan(dir / "seq" / io::scanFileName(0));
  const io::Scan out = io::readScan(dir / "out" / io::scanFileName(0));
  ASSERT_EQ(out.cloud->size(), rows.size());
  const bool extrapolate =
      std::string(c.outside) == "extrapolate" || std::string(c.outside) == "linear";
  std::size_t nan_rows = 0, outside_rows = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    SCOPED_TRACE(i);
    const auto& p = (*out.cloud)[i];
    if (std::isnan(rows[i].second)) {
      ++nan_rows;
      EXPECT_TRUE(std::isnan(p.x));
      continue;
    }
    // The PCD holds the reading as float coordinates: correct sees r_f, not the LUT's reading;
    // the difference moves the range by at most |r - r_f| f'^-1 plus float rounding of the output.
    const auto& q = (*raw.cloud)[i];
    const double r_f = std::hypot(static_cast<double>(q.x), static_cast<double>(q.y));
    const double out_range = std::hypot(static_cast<double>(p.x), static_cast<double>(p.y));
    if (!extrapolate && (r_f < m.model.bias(0.5) || r_f > m.model.bias(8.0))) {
      // An end row whose float reading fell just outside the corrected readings: kept as read.
      ++outside_rows;
      EXPECT_TRUE(i == 0 || i + 1 == rows.size());
      EXPECT_NEAR(out_range, r_f, 1e-6);
      continue;
    }
    const double tolerance = 2.0 * std::abs(r_f - rows[i].first) + 4e-6;
    EXPECT_NEAR(out_range, rows[i].second, tolerance);
  }
  EXPECT_EQ(nan_rows, 0u);
  EXPECT_LE(outside_rows, 2u);
}

INSTANTIATE_TEST_SUITE_P(Policies, LutEqualsCorrect,
                         ::testing::Values(LutCase{"ls", "keep"}, LutCase{"ml", "keep"},
                                           LutCase{"ls", "extrapolate"}, LutCase{"ls", "linear"},
                                           LutCase{"ml", "linear"}),
                         [](const auto& p) {
                           return std::string(p.param.inversion) + "_" + p.param.outside;
                         });

TEST(Export, TheDefaultContinuesTheTangentOverTheSensorsRangeWindow) {
  TempDir dir;
  const CalibrationModel m = polynomialModel("s", 0);
  io::writeModel(dir / "model.json", m);
  const CliResult r = runCli("export " + (dir / "model.json").string() + " --format lut");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = readLut(r.out);
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows.front().first, 0.15);
  EXPECT_EQ(rows.back().first, 12.0);
  const auto& f = m.model.bias;
  std::size_t beyond = 0;
  for (const auto& [y, d] : rows) {
    if (y >= f(0.5) && y <= f(8.0)) continue;
    const double edge = y < f(0.5) ? 0.5 : 8.0;
    // 9 significant digits
    EXPECT_NEAR(d, edge + (y - f(edge)) / f.derivative(edge), 1e-8 * d + 1e-9) << y;
    ++beyond;
  }
  EXPECT_GT(beyond, 100u);
}

TEST(Export, ExtrapolateSpansTheSensorsRangeWindow) {
  TempDir dir;
  io::writeModel(dir / "model.json", polynomialModel("s", 0));
  const CliResult r =
      runCli("export " + (dir / "model.json").string() + " --format lut --outside extrapolate");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = readLut(r.out);
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows.front().first, 0.15);
  EXPECT_EQ(rows.back().first, 12.0);
}

TEST(Export, RefusesBadInputWithExitCodes) {
  TempDir dir;
  CalibrationModel m = polynomialModel("s", 0);
  io::writeModel(dir / "model.json", m);
  const std::string model = (dir / "model.json").string();
  EXPECT_EQ(runCli("export " + model + " --format lut --step 0").exit_code, 2);
  EXPECT_EQ(runCli("export " + model + " --format lut --step 1e-9").exit_code, 2);
  EXPECT_EQ(runCli("export " + model + " --format yaml --step 0.1").exit_code, 2);
  EXPECT_EQ(runCli("export " + model + " --format csv").exit_code, 2);
  writeFile(dir / "taken.csv", "keep me");
  const CliResult taken =
      runCli("export " + model + " --format lut -o " + (dir / "taken.csv").string());
  EXPECT_EQ(taken.exit_code, 2);
  EXPECT_NE(taken.err.find("--overwrite"), std::string::npos) << taken.err;
  EXPECT_EQ(readFile(dir / "taken.csv"), "keep me");
  // ML needs the squared noise law.
  m.model.noise.kind = NoiseKind::constant;
  io::writeModel(dir / "constant.json", m);
  const CliResult ml =
      runCli("export " + (dir / "constant.json").string() + " --format lut --inversion ml");
  EXPECT_EQ(ml.exit_code, 2);
  EXPECT_NE(ml.err.find("--inversion"), std::string::npos) << ml.err;
  // A polynomial that turns back inside its fitted range: the data cannot support a table.
  m = polynomialModel("s", 0);
  m.model.bias.alpha = {0.0, 1.0, -0.1};  // f' = 0 at d = 5 m, inside 0.5-8 m
  io::writeModel(dir / "turning.json", m);
  const CliResult turning = runCli("export " + (dir / "turning.json").string() + " --format yaml");
  EXPECT_EQ(turning.exit_code, 3);
  EXPECT_NE(turning.err.find("bias.alpha"), std::string::npos) << turning.err;
}

// A rig model holds one model per sensor: `--sensor` picks a block by name, topic or frame, and the
// table is the one that block's model gives exported alone (the oracle: a single-sensor file).
TEST(Export, SensorPicksOneBlockOfARigModel) {
  TempDir dir;
  const io::RigModel rig = twoLidarModel("/scan_front", "/scan_back");
  io::writeRigModel(dir / "rig.json", rig);
  const std::string model = (dir / "rig.json").string();
  for (std::size_t k = 0; k < rig.sensors.size(); ++k) {
    const io::RigModelSensor& s = rig.sensors[k];
    SCOPED_TRACE(s.name);
    io::writeModel(dir / (s.name + ".json"), s.model);
    const CliResult alone =
        runCli("export " + (dir / (s.name + ".json")).string() + " --format lut --step 0.1");
    ASSERT_EQ(alone.exit_code, 0) << alone.err;
    for (const std::string& key : {s.name, s.topic, s.frame_id}) {
      const CliResult r = runCli("export " + model + " --format lut --step 0.1 --sensor " + key);
      ASSERT_EQ(r.exit_code, 0) << key << ": " << r.err;
      EXPECT_EQ(r.out, alone.out) << key;
    }
    const CliResult yaml = runCli("export " + model + " --format yaml --sensor " + s.name);
    ASSERT_EQ(yaml.exit_code, 0) << yaml.err;
    EXPECT_EQ(yamlList(yaml.out, "bias_alpha"), s.model.model.bias.alpha);
    EXPECT_NE(yaml.out.find("(sensor " + s.name + ")"), std::string::npos) << yaml.out;
  }
  // Without --sensor, or naming no block: exit 2, naming the blocks it holds.
  const CliResult none = runCli("export " + model + " --format lut");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("--sensor"), std::string::npos) << none.err;
  const CliResult other = runCli("export " + model + " --format lut --sensor side");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.err.find("front"), std::string::npos) << other.err;
}

}  // namespace
}  // namespace lidarcal::test
