// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal diagnose` end to end on stop-and-go sequences: simulated scans through the detector,
// the output files, determinism, a long sequence's window, mixed pixels and dark poles named from
// the scans, errors; `calibrate --effects`.

#include <cmath>
#include <filesystem>
#include <functional>
#include <random>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/rng.hpp"
#include "diagnose_cli_util.hpp"
#include "io/model_io.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;
namespace fs = std::filesystem;

class CliDiagnose : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    simulate(writeScene(dir_->path(), "heading",
                        [](nlohmann::json& s) { s["path"]["sigma_psi_deg"] = 1.2; }),
             dir_->path() / "heading", 5);
    simulate(writeScene(dir_->path(), "clean", [](nlohmann::json&) {}), dir_->path() / "clean", 6);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static fs::path at(const std::string& p) { return dir_->path() / p; }
  static TempDir* dir_;
};
TempDir* CliDiagnose::dir_ = nullptr;

TEST_F(CliDiagnose, NamesAHeadingErrorInDetectedScansAndWritesTheReport) {
  TempDir out;
  const auto before = test::snapshot(at("heading"));
  const auto r = runCli("diagnose -q " + at("heading/scans").string() + " --out " +
                        (out / "d").string() + " --truth " + at("heading/truth.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "heading_error\n");
  EXPECT_TRUE(before == test::snapshot(at("heading")));  // input untouched
  const auto j = json(out / "d/diagnosis.json");
  EXPECT_EQ(j["format"], "lidarcal-diagnosis/1");
  EXPECT_EQ(j["mode"], "sequence");
  EXPECT_EQ(j["primary_cause"], "heading_error");
  EXPECT_EQ(j["settings"]["multiple_testing"], "holm");
  std::set<std::string> names;
  for (const auto& c : j["candidates"]) {
    names.insert(c["effect"].get<std::string>());
    for (const char* key : {"effect", "p_value", "heldout_gain_nats_per_point", "delta_aic",
                            "significant", "identifiable"})
      EXPECT_TRUE(c.contains(key)) << key;
  }
  for (const char* e : {"incidence_noise", "incidence_bias", "landmark_bias", "heading_error",
                        "range_drift", "mixed_pixels", "angle_offset", "range_noise_law"})
    EXPECT_TRUE(names.count(e)) << e;
  EXPECT_FALSE(j["battery"].empty());
  ASSERT_TRUE(j["extended_model"].is_object());
  EXPECT_EQ(j["extended_model"]["effect"], "heading_error");
  // The estimate is the RMS of the refined headings about the commanded ones; the truth is the
  // ten headings the simulator drew (truth.json), whose RMS is itself 1.2 degrees only on average
  // (it scatters by 22 % over 10 draws): compare with the realised RMS (1.40 degrees here). Each
  // stop's heading is pinned by five poles to a few hundredths of a degree, but the heading
  // model's 2-degree prior pulls the refined headings towards the commanded ones (measured: 19 %
  // below the realised RMS); allow 25 % (was 50 % of the nominal 1.2).
  double ss = 0.0;
  const auto truth = json(at("heading/truth.json"));
  for (const auto& st : truth["stops"]) {
    const double psi =
        st["actual"]["yaw_rad"].get<double>() - st["commanded"]["yaw_rad"].get<double>();
    ss += psi * psi;
  }
  const double realised_deg =
      std::sqrt(ss / static_cast<double>(truth["stops"].size())) * 180.0 / M_PI;
  EXPECT_NEAR(j["extended_model"]["scene_keys"]["path.sigma_psi_deg"].get<double>(), realised_deg,
              0.25 * realised_deg)
      << "realised " << realised_deg << " degrees";
  EXPECT_GT(j["gain"]["heldout_nats_per_point"].get<double>(), 0.0);
  EXPECT_GT(j["gain"]["calibration_mse_ratio"]["baseline"].get<double>(), 0.0);
  EXPECT_TRUE(fs::exists(out / "d/report.md"));
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    EXPECT_TRUE(fs::exists(out / "d/residuals_range.png"));
    EXPECT_TRUE(fs::exists(out / "d/residual_distribution.png"));
  }
}

TEST_F(CliDiagnose, CleanDataHasNoCauseAndTheSameSeedGivesTheSameBytes) {
  TempDir out;
  const std::string args = " " + at("clean/scans").string() + " --replicas 9 --seed 4 --out ";
  const auto r1 = runCli("diagnose -q" + args + (out / "a").string());
  const auto r2 = runCli("diagnose -q" + args + (out / "b").string());
  ASSERT_EQ(r1.exit_code, 0) << r1.err;
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_EQ(r1.out, "none\n");
  const auto j = json(out / "a/diagnosis.json");
  EXPECT_TRUE(j["extended_model"].is_null());
  EXPECT_EQ(test::readFile(out / "a/diagnosis.json"), test::readFile(out / "b/diagnosis.json"));
}

TEST_F(CliDiagnose, ALongSequenceIsDiagnosedOverItsLeadingStopsAndSaysSo) {
  // The whole clean sequence first (no cap), then capped at about half its readings.
  TempDir out;
  const std::string args = " " + at("clean/scans").string() + " --replicas 5 --out ";
  const auto whole = runCli("diagnose -q --max-readings 0" + args + (out / "all").string());
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  const auto all = json(out / "all/diagnosis.json")["data"];
  EXPECT_FALSE(all.contains("selection"));
  const int total = all["readings"].get<int>(), cap = total / 2;
  const auto r =
      runCli("diagnose -q --max-readings " + std::to_string(cap) + args + (out / "half").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto half = json(out / "half/diagnosis.json")["data"];
  EXPECT_LE(half["readings"].get<int>(), cap);
  EXPECT_GT(half["readings"].get<int>(), cap / 2);  // whole stops up to the cap, not fewer
  EXPECT_LT(half["stops"].get<int>(), all["stops"].get<int>());
  EXPECT_LT(half["scans"].get<int>(), all["scans"].get<int>());
  const std::string said = "the first " + std::to_string(half["stops"].get<int>()) + " of " +
                           std::to_string(all["stops"].get<int>()) + " stops";
  EXPECT_NE(half["selection"].get<std::string>().find(said), std::string::npos)
      << half["selection"];
  EXPECT_NE(test::readFile(out / "half/report.md").find(said), std::string::npos);
  // A cap below one stop's readings keeps the two stops a sequence diagnosis needs.
  const auto tiny =
      runCli("diagnose -q --mode sequence --max-readings 1" + args + (out / "tiny").string());
  EXPECT_TRUE(tiny.exit_code == 0 || tiny.exit_code == 3) << tiny.exit_code << " " << tiny.err;
  EXPECT_EQ(json(out / "tiny/diagnosis.json")["data"]["stops"].get<int>(), 2);
}

TEST(CliDiagnoseStopAndGo, MixedPixelsAtPoleEdgesInTheScansAreNamed) {
  // The paper field through the scan simulator and the detector, 5-10 % of the beams at a pole's
  // edge reading between the pole and the background: the readings off the circle are kept
  // beside their sightings when no other scan of the stop sees a surface there. Fraction and
  // simulator seed from a seed this test does not read (measured: 8 of 8 such fields named,
  // their clean twins none; docs/results/hidden-effects.md).
  TempDir dir;
  auto rng = makeRng(20261128, 31);
  const double fraction = std::uniform_real_distribution<double>(0.05, 0.10)(rng);
  const int seed = std::uniform_int_distribution<int>(100, 100000)(rng);
  simulate(writeScene(dir.path(), "mixed",
                      [&](nlohmann::json& s) {
                        s["sensor"]["effects"] = {{"mixed_pixel_fraction", fraction}};
                      }),
           dir / "mixed", seed);
  const auto r = runCli("diagnose -q " + (dir / "mixed/scans").string() + " --replicas 9 --out " +
                        (dir / "d").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "mixed_pixels\n") << "seed " << seed << ", fraction " << fraction;
  EXPECT_GT(json(dir / "d/diagnosis.json")["data"]["readings_beside_poles"].get<int>(), 0);
}

TEST(CliDiagnoseIntensity, DarkPolesAreNamedFromTheScansIntensitiesAndCalibratedWithTheirTerm) {
  // The whole chain: the simulator writes each pole's intensity into the scans' intensity field,
  // the detection carries it into the sightings, and the noise grows as (80 / I)^1 on poles of
  // intensity 20-240 (the darkest reads 4 times as noisy as one of 80).
  TempDir dir;
  const double intensity[] = {20.0, 180.0, 60.0, 240.0, 40.0};
  simulate(writeScene(dir.path(), "dark",
                      [&](nlohmann::json& s) {
                        for (std::size_t l = 0; l < s["landmarks"].size(); ++l)
                          s["landmarks"][l]["intensity"] = intensity[l % 5];
                        s["sensor"]["effects"] = {{"dark_noise_exponent", 1.0},
                                                  {"dark_reference_intensity", 80.0}};
                      }),
           dir / "dark", 7);
  ASSERT_NE(test::readFile(dir / "dark/scans/scan_000000.pcd").find("intensity"),
            std::string::npos);
  auto r = runCli("diagnose -q " + (dir / "dark/scans").string() + " --out " +
                  (dir / "d").string() + " --replicas 5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "dark_surface\n");
  const auto j = json(dir / "d/diagnosis.json");
  EXPECT_NEAR(j["extended_model"]["scene_keys"]["sensor.effects.dark_noise_exponent"].get<double>(),
              1.0, 0.25);
  r = runCli("calibrate -q " + (dir / "dark/scans").string() + " --out " +
             (dir / "m.json").string() + " --effects dark_surface");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto m = json(dir / "m.json");
  EXPECT_NEAR(m["effects"]["dark_noise_exponent"].get<double>(), 1.0, 0.25);
  EXPECT_GT(m["effects"]["dark_reference_intensity"].get<double>(), 20.0);
}

TEST(CliDiagnoseErrors, BadInputsExplainThemselves) {
  TempDir dir;
  auto r = runCli("diagnose -q " + (dir / "missing").string() + " --out " + (dir / "d").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const fs::path scene = writeScene(dir.path(), "one", [](nlohmann::json& s) {
    s["path"]["stops"] = 1;
    s["path"]["scans_per_stop"] = 12;
  });
  simulate(scene, dir / "one", 1);
  r = runCli("diagnose -q " + (dir / "one/scans").string() + " --out " + (dir / "d").string() +
             " --mode sequence");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("two stops"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "d"));
  r = runCli("diagnose -q " + (dir / "one/scans").string() + " --out " + (dir / "d").string() +
             " --candidates wobble");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("wobble"), std::string::npos) << r.err;
}

TEST(CliCalibrateEffects, TheCalibrationUsesAnEffectTermAndWritesIt) {
  TempDir dir;
  const fs::path scene = writeScene(dir.path(), "offsets", [](nlohmann::json& s) {
    s["landmarks"][1]["range_offset_m"] = 0.04;
    s["landmarks"][3]["range_offset_m"] = -0.03;
  });
  simulate(scene, dir / "s", 2, "--scans-per-stop 3");
  auto r = runCli("calibrate -q " + (dir / "s/scans").string() + " --out " +
                  (dir / "m.json").string() + " --effects landmark_bias");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto m = io::readModel(dir / "m.json");
  ASSERT_EQ(m.effects.size(), 5u);
  const double mean = (0.04 - 0.03) / 5.0;
  // Landmark ids follow detection order; the offsets +0.04 and -0.03 are among them.
  double hi = -1, lo = 1;
  for (const auto& [k, v] : m.effects) {
    hi = std::max(hi, v);
    lo = std::min(lo, v);
  }
  EXPECT_NEAR(hi, 0.04 - mean, 0.01);
  EXPECT_NEAR(lo, -0.03 - mean, 0.01);
  r = runCli("calibrate -q " + (dir / "s/scans").string() + " --out " + (dir / "n.json").string() +
             " --effects wobble");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("wobble"), std::string::npos);
  // The remedy lists every effect term there is.
  EXPECT_NE(r.err.find("odometry_scale"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("quantisation"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("dark_surface"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "n.json"));
}

}  // namespace
}  // namespace lidarcal
