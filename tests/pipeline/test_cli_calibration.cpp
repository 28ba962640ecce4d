// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal run`, `calibrate`, `correct` and `evaluate` end to end on simulated sequences.

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "calibration/inversion.hpp"
#include "io/model_io.hpp"
#include "io/pcd_scan.hpp"
#include "io/sequence.hpp"
#include "io/true_ranges.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;

std::string scene(const char* name = "paper_field.json") {
  return (test::sourceDir() / "data/scenes" / name).string();
}

/// A small simulated sequence of the paper's field: 10 stops, 3 scans each.
void simulate(const std::filesystem::path& dir, int seed,
              const char* scene_name = "paper_field.json") {
  const auto r = runCli("simulate -q --scene " + scene(scene_name) + " --out " + dir.string() +
                        " --seed " + std::to_string(seed) + " --scans-per-stop 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

nlohmann::json json(const std::filesystem::path& p) {
  return nlohmann::json::parse(test::readFile(p));
}

class CliCalibration : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    simulate(dir_->path() / "a", 21);
    simulate(dir_->path() / "b", 22);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::filesystem::path a() { return dir_->path() / "a"; }
  static std::filesystem::path b() { return dir_->path() / "b"; }
  static TempDir* dir_;
};
TempDir* CliCalibration::dir_ = nullptr;

TEST_F(CliCalibration, RunCalibratesCorrectsAndReportsWithTheTruthFoundNextToTheScans) {
  TempDir out;
  const auto before = test::snapshot(a());
  const auto r = runCli("run -q " + (a() / "scans").string() + " --out " + (out / "o").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(before == test::snapshot(a()));  // input untouched
  const auto model = io::readModel(out / "o/model.json");
  EXPECT_EQ(model.method, "joint");
  EXPECT_EQ(model.model.bias.order(), 2);
  // The corrected sequence has the same files.
  const auto raw = io::openSequence(a() / "scans");
  const auto cor = io::openSequence(out / "o/corrected");
  ASSERT_EQ(raw.scans.size(), cor.scans.size());
  for (std::size_t i = 0; i < raw.scans.size(); ++i)
    EXPECT_EQ(raw.scans[i].name(), cor.scans[i].name());
  // Corrected ranges are far closer to the truth: the bias is 20 cm at 3 m, the noise 2 cm.
  const auto summary = json(out / "o/summary.json");
  EXPECT_GT(summary["evaluation"]["landmarks"]["mse_ratio"].get<double>(), 30.0);
  const std::string report = test::readFile(out / "o/report/report.md");
  EXPECT_NE(report.find("## The calibrated model"), std::string::npos);
  EXPECT_NE(report.find("## Against the truth"), std::string::npos);
  EXPECT_NE(report.find("## Order selection"), std::string::npos);
}

TEST_F(CliCalibration, CorrectMovesEveryPointAlongItsBeamToTheInverseOfTheBiasAndKeepsNaNAndOrder) {
  // Readings inside the range the model was fitted over (model.json fitted_range) move to f^-1 of
  // the reading; those beyond it to f continued as its tangent at the nearer edge (the default).
  TempDir out;
  ASSERT_EQ(
      runCli("calibrate -q " + (a() / "scans").string() + " --out " + (out / "m.json").string())
          .exit_code,
      0);
  // Correct the other sequence (a different draw of the same sensor).
  const auto r = runCli("correct -q " + (b() / "scans").string() + " --model " +
                        (out / "m.json").string() + " --out " + (out / "c").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto model = io::readModel(out / "m.json");
  const calibration::RangeInverter inv(
      model.model, calibration::inversionWindow(model.model, calibration::InversionMethod::ls));
  const auto raw = io::openSequence(b() / "scans");
  std::size_t continued = 0, moved = 0;
  for (std::size_t i : {0u, 17u, 29u}) {
    const io::Scan rs = io::readScan(raw.scans[i].path);
    const io::Scan cs = io::readScan(out / "c" / raw.scans[i].name());
    ASSERT_EQ(rs.cloud->size(), cs.cloud->size());
    EXPECT_NEAR(cs.viewpoint.x_m, rs.viewpoint.x_m, 1e-9);
    for (std::size_t k = 0; k < rs.cloud->size(); ++k) {
      const auto& p = (*rs.cloud)[k];
      const auto& q = (*cs.cloud)[k];
      if (!std::isfinite(p.x)) {
        EXPECT_FALSE(std::isfinite(q.x));
        continue;
      }
      ASSERT_TRUE(std::isfinite(q.x));
      const double rr = std::hypot(p.x, p.y), rc = std::hypot(q.x, q.y);
      EXPECT_NEAR(std::atan2(q.y, q.x), std::atan2(p.y, p.x), 1e-5);  // same beam
      ASSERT_TRUE(model.fitted_range_m.has_value());
      const auto [lo, hi] = *model.fitted_range_m;
      const auto& f = model.model.bias;
      ASSERT_EQ(cs.correction.size(), cs.cloud->size());
      if (rr < f(lo) || rr > f(hi)) {
        const double edge = rr < f(lo) ? lo : hi;
        // the tangent at the edge
        EXPECT_NEAR(rc, edge + (rr - f(edge)) / f.derivative(edge), 1e-5);
        EXPECT_EQ(cs.correction[k], io::PointCorrection::extrapolated);
        ++continued;
        continue;
      }
      ++moved;
      EXPECT_EQ(cs.correction[k], io::PointCorrection::corrected);
      EXPECT_NEAR(rc, *inv.invert(rr), 1e-5);       // corrected distance
      EXPECT_NEAR(model.model.bias(rc), rr, 1e-5);  // f(corrected) = raw
    }
  }
  EXPECT_GT(moved, 100u);
  EXPECT_GT(continued, 10u);  // the walls beyond the farthest pole
  // Evaluate: the correction of an independent sequence beats the raw readings by far.
  const auto e =
      runCli("evaluate " + (out / "c").string() + " --truth " + (b() / "truth.json").string());
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const auto j = nlohmann::json::parse(e.out);
  EXPECT_GT(j["landmarks"]["mse_ratio"].get<double>(), 30.0);
  EXPECT_LT(j["all"]["nmse_corrected"].get<double>(), j["all"]["nmse_raw"].get<double>());
  // The walls lie mostly beyond the farthest pole and were never used to calibrate: continued
  // from the edge by default they gain far more than kept as read.
  EXPECT_GT(j["walls"]["mse_ratio"].get<double>(), 10.0);
  EXPECT_GT(j["beyond_fitted_range"]["n"].get<double>(), 10.0);
  ASSERT_EQ(runCli("correct -q " + (b() / "scans").string() + " --model " +
                   (out / "m.json").string() + " --outside keep --out " + (out / "k").string())
                .exit_code,
            0);
  const auto k =
      runCli("evaluate " + (out / "k").string() + " --truth " + (b() / "truth.json").string());
  ASSERT_EQ(k.exit_code, 0) << k.err;
  EXPECT_LT(nlohmann::json::parse(k.out)["walls"]["mse_ratio"].get<double>(), 3.0);
}

/// Raw and corrected ranges of the beams of one class against the truth.
struct Scored {
  double raw2 = 0.0, cor2 = 0.0;
  std::size_t n = 0;
  void add(double truth, double raw, double cor) {
    raw2 += (raw - truth) * (raw - truth);
    cor2 += (cor - truth) * (cor - truth);
    ++n;
  }
  double ratio() const { return raw2 / cor2; }
};

TEST_F(CliCalibration, RunsFiguresAreThoseOfTheScansItWrote) {
  TempDir out;
  const auto r = runCli("run -q " + (a() / "scans").string() + " --out " + (out / "o").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Score the written scans here, from the files alone.
  const auto raw = io::openSequence(a() / "scans");
  const auto truth = io::readTrueRanges(a() / "true_ranges.csv");
  const std::size_t beams = truth.size() / raw.scans.size();
  Scored landmarks, walls, all, beyond;
  std::size_t corrected = 0, extrapolated = 0;
  for (std::size_t i = 0; i < raw.scans.size(); ++i) {
    const io::Scan rs = io::readScan(raw.scans[i].path);
    const io::Scan cs = io::readScan(out / "o/corrected" / raw.scans[i].name());
    ASSERT_EQ(cs.correction.size(), rs.cloud->size());
    for (std::size_t b = 0; b < rs.cloud->size(); ++b) {
      const auto& t = truth[i * beams + b];
      const auto &p = (*rs.cloud)[b], &q = (*cs.cloud)[b];
      if (!std::isfinite(p.x) || !std::isfinite(q.x) || !std::isfinite(t.range_m)) continue;
      const double y = std::hypot(p.x, p.y), c = std::hypot(q.x, q.y);
      all.add(t.range_m, y, c);
      if (t.target == io::TargetKind::landmark) landmarks.add(t.range_m, y, c);
      if (t.target == io::TargetKind::wall) walls.add(t.range_m, y, c);
      if (cs.correction[b] == io::PointCorrection::extrapolated)
        beyond.add(t.range_m, y, c), ++extrapolated;
      if (cs.correction[b] == io::PointCorrection::corrected) ++corrected;
    }
  }
  const auto summary = json(out / "o/summary.json");
  const auto& e = summary["evaluation"];
  EXPECT_EQ(summary["corrected_returns"].get<std::size_t>(), corrected);
  EXPECT_EQ(summary["extrapolated_returns"].get<std::size_t>(), extrapolated);
  EXPECT_GT(extrapolated, 100u);
  const std::pair<const char*, const Scored*> rows[] = {{"landmarks", &landmarks},
                                                        {"walls", &walls},
                                                        {"all", &all},
                                                        {"beyond_fitted_range", &beyond}};
  for (const auto& [name, s] : rows) {
    SCOPED_TRACE(name);
    EXPECT_EQ(e[name]["n"].get<std::size_t>(), s->n);
    EXPECT_NEAR(e[name]["mse_ratio"].get<double>(), s->ratio(), 1e-6 * s->ratio());
  }
  // The report's table of the written scans shows the same MSE ratios.
  const std::string report = test::readFile(out / "o/report/report.md");
  char cell[64];
  std::snprintf(cell, sizeof cell, "| %.2f |\n", all.ratio());
  EXPECT_NE(report.find(std::string("| all | ") + std::to_string(all.n)), std::string::npos);
  EXPECT_NE(report.find(cell), std::string::npos) << cell;
}

TEST_F(CliCalibration, AWallCrossingTheEdgeOfTheFittedRangeHasNoStep) {
  // Neighbouring beams on one wall whose true distances straddle the far edge of the fitted range:
  // their errors against the truth differ only by the readings' noise. Kept as read, the one
  // beyond would jump by the sensor's bias there (about half a metre). The beams are chosen by
  // their true distance: chosen by their noisy reading, the one read beyond the edge would be the
  // one whose noise is the larger.
  TempDir out;
  const std::string model = (out / "m.json").string();
  ASSERT_EQ(runCli("calibrate -q " + (a() / "scans").string() + " --out " + model).exit_code, 0);
  const auto m = io::readModel(model);
  const auto raw = io::openSequence(b() / "scans");
  const auto truth = io::readTrueRanges(b() / "true_ranges.csv");
  const std::size_t beams = truth.size() / raw.scans.size();
  auto steps = [&](const std::string& outside) {
    const std::string dir = (out / outside).string();
    EXPECT_EQ(runCli("correct -q " + (b() / "scans").string() + " --model " + model +
                     " --outside " + outside + " --out " + dir)
                  .exit_code,
              0);
    double sum = 0.0, variance = 0.0;  // of the error steps, and of the noise expected in them
    std::size_t n = 0;
    for (std::size_t i = 0; i < raw.scans.size(); ++i) {
      const io::Scan cs = io::readScan(std::filesystem::path(dir) / raw.scans[i].name());
      for (std::size_t b = 0; b + 1 < cs.cloud->size(); ++b) {
        const auto &t0 = truth[i * beams + b], &t1 = truth[i * beams + b + 1];
        const double edge = m.fitted_range_m->second;
        const bool crossing = (t0.range_m <= edge) != (t1.range_m <= edge);
        const auto &p0 = (*cs.cloud)[b], &p1 = (*cs.cloud)[b + 1];
        if (!crossing || t0.target != io::TargetKind::wall || t1.target != t0.target ||
            t1.target_id != t0.target_id || !std::isfinite(p0.x) || !std::isfinite(p1.x))
          continue;
        const double e0 = std::hypot(p0.x, p0.y) - t0.range_m,
                     e1 = std::hypot(p1.x, p1.y) - t1.range_m;
        sum += t0.range_m <= edge ? e1 - e0 : e0 - e1;  // beyond minus inside
        const double s0 =
            m.model.noise.stddev(t0.range_m, m.model.bias) / m.model.bias.derivative(t0.range_m);
        const double s1 =
            m.model.noise.stddev(t1.range_m, m.model.bias) / m.model.bias.derivative(t1.range_m);
        variance += s0 * s0 + s1 * s1;
        ++n;
      }
    }
    EXPECT_GT(n, 5u) << outside;
    return std::make_pair(sum / static_cast<double>(n),
                          std::sqrt(variance) / static_cast<double>(n));
  };
  const auto [step, sigma] = steps("linear");
  EXPECT_LT(std::abs(step), 3.0 * sigma) << "mean step " << step << " m, sigma " << sigma << " m";
  const auto [kept_step, kept_sigma] = steps("keep");
  // what the test would see without the continuation
  EXPECT_GT(std::abs(kept_step), 10.0 * kept_sigma);
}

TEST_F(CliCalibration, OracleRecoversTheSimulatedBias) {
  TempDir out;
  ASSERT_EQ(runCli("calibrate -q " + (a() / "scans").string() + " --truth " +
                   (a() / "truth.json").string() + " --out " + (out / "o.json").string())
                .exit_code,
            0);
  const auto m = io::readModel(out / "o.json");
  EXPECT_EQ(m.method, "oracle");
  const BiasPolynomial truth{{0.0525, 0.8838, 0.0584}};
  for (double d : {0.8, 1.5, 2.5, 3.5}) EXPECT_NEAR(m.model.bias(d), truth(d), 0.01) << d;
}

TEST_F(CliCalibration, SameInputGivesTheSameModelAndCorrectedBytes) {
  TempDir out;
  for (const char* n : {"x", "y"})
    ASSERT_EQ(
        runCli("run -q " + (a() / "scans").string() + " --out " + (out / n).string()).exit_code, 0);
  EXPECT_EQ(test::readFile(out / "x/model.json"), test::readFile(out / "y/model.json"));
  EXPECT_TRUE(test::snapshot(out / "x/corrected") == test::snapshot(out / "y/corrected"));
}

// Where the program's memory happens to lie must not reach the output: Ceres orders a
// covariance's columns by the parameter blocks' addresses, and before the blocks were put in one
// array the standard errors' last digits changed with the length of the output path or the
// spelling of the input path (the binary of commit 27095fc fails both comparisons here).
TEST_F(CliCalibration, ModelBytesDoNotDependOnHowThePathsAreSpelled) {
  TempDir out;
  const std::string scans = (a() / "scans").string();
  const std::string long_name(120, 'x');
  ASSERT_EQ(runCli("run -q " + scans + " --out " + (out / "o").string()).exit_code, 0);
  ASSERT_EQ(runCli("run -q " + scans + " --out " + (out / long_name).string()).exit_code, 0);
  ASSERT_EQ(
      runCli("run -q " + (a() / "./scans/").string() + " --out " + (out / "p").string()).exit_code,
      0);
  const std::string model = test::readFile(out / "o/model.json");
  EXPECT_EQ(model, test::readFile(out / long_name / "model.json"));
  EXPECT_EQ(model, test::readFile(out / "p/model.json"));
}

TEST_F(CliCalibration, CorrectRefusesAModelOfAnotherSensor) {
  TempDir out;
  ASSERT_EQ(
      runCli("calibrate -q " + (a() / "scans").string() + " --out " + (out / "m.json").string())
          .exit_code,
      0);
  auto j = json(out / "m.json");
  j["sensor"]["beams"] = 720;
  test::writeFile(out / "beams.json", j.dump());
  auto r = runCli("correct " + (b() / "scans").string() + " --model " +
                  (out / "beams.json").string() + " --out " + (out / "c1").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("has 360 beams"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out / "c1"));
  j = json(out / "m.json");
  j["sensor"]["range_max_m"] = 12.0;
  test::writeFile(out / "range.json", j.dump());
  r = runCli("correct " + (b() / "scans").string() + " --model " + (out / "range.json").string() +
             " --out " + (out / "c2").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("range limits differ"), std::string::npos) << r.err;
}

TEST_F(CliCalibration, CorrectRefusesABiasThatCannotBeInvertedAndAMalformedModel) {
  TempDir out;
  ASSERT_EQ(
      runCli("calibrate -q " + (a() / "scans").string() + " --out " + (out / "m.json").string())
          .exit_code,
      0);
  auto j = json(out / "m.json");
  j["bias"]["alpha"] = {0.0, 2.0, -0.3};  // peaks at d = 3.3 m with f = 3.3 m < 6 m
  test::writeFile(out / "peak.json", j.dump());
  auto r = runCli("correct " + (b() / "scans").string() + " --model " +
                  (out / "peak.json").string() + " --out " + (out / "c").string());
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("bias.alpha"), std::string::npos) << r.err;
  j = json(out / "m.json");
  j["noise"]["kind"] = "pink";
  test::writeFile(out / "bad.json", j.dump());
  r = runCli("correct " + (b() / "scans").string() + " --model " + (out / "bad.json").string() +
             " --out " + (out / "c").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("noise.kind"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out / "c"));
}

TEST_F(CliCalibration, OutputInsideTheInputIsRefused) {
  const auto before = test::snapshot(a());
  const auto r =
      runCli("run " + (a() / "scans").string() + " --out " + (a() / "scans/out").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("inside it"), std::string::npos) << r.err;
  EXPECT_TRUE(before == test::snapshot(a()));
}

TEST(CliCalibrationNoLandmark, ASequenceWithoutPolesCannotBeCalibrated) {
  TempDir dir;
  test::writeFile(dir / "walls.json", R"({"sensor": {"range_min_m": 0.2, "range_max_m": 6.0,
      "bias_alpha": [0.0525, 0.8838, 0.0584]}, "path": {"stops": 4, "scans_per_stop": 1},
      "walls": [{"x0_m": -2, "y0_m": -2, "x1_m": 3, "y1_m": -2}, {"x0_m": 3, "y0_m": -2, "x1_m": 3, "y1_m": 2}]})");
  ASSERT_EQ(runCli("simulate -q --scene " + (dir / "walls.json").string() + " --out " +
                   (dir / "s").string())
                .exit_code,
            0);
  const auto r =
      runCli("calibrate " + (dir / "s/scans").string() + " --out " + (dir / "m.json").string());
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("no landmark"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "m.json"));
}

}  // namespace
}  // namespace lidarcal
