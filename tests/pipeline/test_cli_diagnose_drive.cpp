// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal diagnose` on drives (a robot that never stops, a pose per scan under the motion prior):
// clean drives name no effect, hidden effects among thin poles are named at their size, a yawed
// lidar from its odometry steps, the odometry's noise fitted from the drive's own steps.

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

TEST(CliDiagnoseDriving,
     PosesThatSeeNoPoleKeepTheHeldOutGainsFiniteAndTheReplicasDriftLikeTheData) {
  // A robot driving without stopping (a pose per scan, chained by the odometry: the motion
  // prior) whose sensor reaches 1 m only, so that some poses see no pole. The odometry's
  // held-out likelihood assumed a pose prior per stop; such a pose sits where its neighbours put
  // it, and its "held-out odometry" came out at -1e13 nats (CARMEN logs). A held-out gain is a
  // log-likelihood ratio per reading: a few nats at most for any effect a lidar can have.
  TempDir dir;
  nlohmann::json s = json(test::sourceDir() / "data/scenes/driving_small_poles.json");
  s["sensor"]["range_max_m"] = 1.0;
  test::writeFile(dir / "short.json", s.dump(1));
  simulate(dir / "short.json", dir / "drive", 3);
  const auto r = runCli("diagnose -q " + (dir / "drive/scans").string() + " --replicas 5 --out " +
                        (dir / "d").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = json(dir / "d/diagnosis.json");
  EXPECT_EQ(j["baseline"]["fitted"]["motion_prior"], 1.0);
  int finite = 0;
  for (const auto& c : j["candidates"]) {
    if (c["heldout_gain_nats_per_point"].is_null()) continue;
    ++finite;
    EXPECT_LT(std::abs(c["heldout_gain_nats_per_point"].get<double>()), 5.0) << c["effect"];
    EXPECT_LT(c["heldout_gain_se"].get<double>(), 5.0) << c["effect"];
  }
  EXPECT_GE(finite, 5);
  EXPECT_EQ(test::readFile(dir / "d/report.md").find("odometry leave-one-stop-out"),
            std::string::npos);
  // The replicas drive their paths as the motion prior says odometry drifts. Drawn around the
  // commanded poses as for stop and go, they disagreed with the data on 4 of the 17 battery
  // statistics at p < 0.01 here (6-8 on the full-range drives of data/scenes), now on 1.
  int small_p = 0;
  for (const auto& b : j["battery"]) small_p += b["p_value"].get<double>() < 0.01;
  EXPECT_LE(small_p, 2) << j["battery"].dump();
  // Odometry drifts in heading as in position, which the motion prior models: the baseline
  // refines the headings under it, so heading_error (free headings) adds nothing and is not a
  // candidate. Held at the drifting odometry's headings, clean drives were named heading_error.
  for (const auto& c : j["candidates"]) {
    if (c["effect"] != "heading_error") continue;
    EXPECT_FALSE(c["applicable"].get<bool>());
    EXPECT_TRUE(c["p_value"].is_null());
  }
  EXPECT_NE(j["primary_cause"], "heading_error");
  // Other candidates count only their own parameters (not the baseline's headings).
  for (const auto& c : j["candidates"])
    if (c["effect"] == "incidence_bias" || c["effect"] == "range_drift") {
      EXPECT_EQ(c["parameters"], 1) << c["effect"];
    }
}

TEST(CliDiagnoseDriving, CleanDrivesNameNoEffectAtItsNull) {
  // A pose per scan, chained by the odometry. What names a clean drive an effect at its null (large
  // poles: mixed_pixels, odometry_scale; thin poles: incidence_bias): edge beams scored at the
  // fitted pose alone, baselines in poorer optima than a candidate's fit, a likelihood ratio
  // between optima. The drive's seed is drawn from a seed this test does not read (the method was
  // developed on seeds 1-60 of the two scenes).
  TempDir dir;
  auto rng = makeRng(20261125, 5);
  std::uniform_int_distribution<int> seed_of(100, 100000);
  for (const std::string scene : {"driving_large_poles", "driving_small_poles"}) {
    test::writeFile(dir / "scene.json",
                    test::readFile(test::sourceDir() / ("data/scenes/" + scene + ".json")));
    const int seed = seed_of(rng);
    simulate(dir / "scene.json", dir / scene, seed);
    const auto r = runCli("diagnose -q " + (dir / scene / "scans").string() +
                          " --replicas 5 --out " + (dir / (scene + "-d")).string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // Clean drives are `none` with large poles and with thin ones (one to three beams per pole;
    // docs/results/hidden-effects.md). Without the held-out predictive distribution over the
    // pose, thin-pole drives get range_noise_law, the in-sample noise being too small.
    EXPECT_EQ(r.out, "none\n") << scene << " seed " << seed;
    const auto j = json(dir / (scene + "-d") / "diagnosis.json");
    expectInSampleEvidence(j, scene + " seed " + std::to_string(seed));
    for (const auto& c : j["candidates"]) {
      // Under the motion prior the likelihood ratio is used for the path terms (a pose per scan:
      // optima; the path terms' evidence is in the odometry steps) and, restricted over the
      // poses, for the noise exponents alone.
      if (c["effect"] != "angle_offset" && c["effect"] != "odometry_scale" &&
          c["effect"] != "incidence_noise" && c["effect"] != "dark_surface") {
        EXPECT_TRUE(c["p_likelihood_ratio"].is_null()) << c["effect"];
      }
      if (!c["significant"].get<bool>()) continue;
      // A significant effect stands two standard errors clear of its null, and a mixed-pixel
      // fraction above the EM's floor.
      const double se = c["standard_error"].get<double>();
      if (c["effect"] == "mixed_pixels") {
        EXPECT_GT(c["estimates"]["mixed_pixel_fraction"].get<double>(), 1.0001e-4);
      } else if (se > 0.0 && c["effect"] != "landmark_bias") {
        const double est = c["estimates"].begin().value().get<double>();
        const double null = c["effect"] == "range_noise_law" ? 2.0 : 0.0;
        // degrees reported, radians fitted
        const double unit = c["effect"] == "angle_offset" ? std::acos(-1.0) / 180.0 : 1.0;
        EXPECT_GT(std::abs(est - null) * unit, 2.0 * se) << scene << " " << c["effect"];
      }
    }
  }
}

TEST(CliDiagnoseDriving, ARangeDriftInAThinPoleDriveIsNamedAtItsSize) {
  // A robot that never stops among thin poles (one to three beams per pole and scan) whose readings
  // drift by 3-4 cm over the drive. Fitted directly on every beam, from the baseline's solution,
  // the drift settled at a third to two thirds of its size, thousands of nats short of its optimum,
  // and incidence_noise was named in 4 of 5 such drives; so every fit under the motion prior also
  // starts with calibrate's smoother problem (SequenceDiagnosis::fitInTwoSteps;
  // docs/results/hidden-effects.md). The drift's size and sign and the simulator's seed come from a
  // seed this test does not read.
  TempDir dir;
  auto rng = makeRng(20261127, 17);
  const double sign = std::bernoulli_distribution(0.5)(rng) ? 1.0 : -1.0;
  const double over_drive_m = std::uniform_real_distribution<double>(0.03, 0.04)(rng);
  const int seed = std::uniform_int_distribution<int>(100, 100000)(rng);
  const double scans =
      json(test::sourceDir() / "data/scenes/driving_small_poles.json")["path"]["scans"]
          .get<double>();
  const double drift = sign * over_drive_m / scans;
  const auto r = diagnoseThinPoleDrive(
      dir.path(),
      [&](nlohmann::json& s) {
        s["sensor"]["effects"] = {{"range_drift_m_per_scan", drift}};
      },
      seed);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "range_drift\n") << "seed " << seed << ", drift " << drift;
  const auto j = json(dir / "d/diagnosis.json");
  for (const auto& c : j["candidates"])
    if (c["effect"] == "range_drift") {
      EXPECT_NEAR(c["estimates"]["range_drift_m_per_scan"].get<double>(), drift,
                  0.1 * std::abs(drift))
          << "seed " << seed;
    }
}

TEST(CliDiagnoseDriving, MixedPixelsBesideThinPolesAreNamed) {
  // 5-10 % of the beams at a thin pole's edge read somewhere between the pole and the background.
  // The detector leaves those readings off the pole's circle, so a diagnosis of its sightings alone
  // never sees them (such drives: none in 5 of 5). The readings beside a pole that lie between it
  // and the background and that no nearby scan sees again are kept as the sighting's outermost
  // readings. The fraction and the simulator's seed come from a seed this test does not read.
  TempDir dir;
  auto rng = makeRng(20261128, 29);
  const double fraction = std::uniform_real_distribution<double>(0.05, 0.10)(rng);
  const int seed = std::uniform_int_distribution<int>(100, 100000)(rng);
  const auto r = diagnoseThinPoleDrive(
      dir.path(),
      [&](nlohmann::json& s) {
        s["sensor"]["effects"] = {{"mixed_pixel_fraction", fraction}};
      },
      seed);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "mixed_pixels\n") << "seed " << seed << ", fraction " << fraction;
  const auto j = json(dir / "d/diagnosis.json");
  EXPECT_GT(j["data"]["readings_beside_poles"].get<int>(), 0);
  EXPECT_NE(test::readFile(dir / "d/report.md").find("beside a pole"), std::string::npos);
  for (const auto& c : j["candidates"])
    if (c["effect"] == "mixed_pixels") {
      // Fitted over the sightings' outermost readings, of which only the mixed pixels beside a
      // detected pole are seen (a mixed pixel on a pole seen by two beams leaves it undetected):
      // below the hidden fraction, above the EM's floor.
      const double f = c["estimates"]["mixed_pixel_fraction"].get<double>();
      EXPECT_GT(f, 0.01) << "seed " << seed;
      EXPECT_LT(f, fraction) << "seed " << seed;
    }
}

TEST(CliDiagnoseDriving, NoiseGrowingTowardsGrazingOnThinPolesIsNamedNotASteeperRangeLaw) {
  // The noise of a reading grows as (1 / cos phi)^gamma with its incidence phi on the pole, gamma
  // 1-1.5, on a robot that never stops among thin poles. Fitted by maximum likelihood with a pose
  // per scan, the exponent reads the residuals as the noise, and the outermost beams that the
  // scan's pose rests on have the smallest: so fitted, clean drives had it at -1 (its lower bound)
  // and 7 of 20 such drives were named a range law 0.2-0.5 steeper than the squared one (4) or none
  // (2 of them). The exponent is therefore estimated by restricted likelihood over the poses
  // (docs/results/hidden-effects.md). Its size and the simulator's seed come from a seed this test
  // does not read.
  TempDir dir;
  auto rng = makeRng(20261128, 31);
  const double gamma = std::uniform_real_distribution<double>(1.0, 1.5)(rng);
  const int seed = std::uniform_int_distribution<int>(100, 100000)(rng);
  const auto r = diagnoseThinPoleDrive(
      dir.path(),
      [&](nlohmann::json& s) {
        s["sensor"]["effects"] = {{"incidence_noise_exponent", gamma}};
      },
      seed);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "incidence_noise\n") << "seed " << seed << ", gamma " << gamma;
  const auto j = json(dir / "d/diagnosis.json");
  for (const auto& c : j["candidates"])
    if (c["effect"] == "incidence_noise") {
      // Still short of the truth (0.52-0.87 for 1.05-1.48 in 20 drives: the beams nearest a
      // pole's tangent move more with the pose than linearly), and clear of zero.
      const double g = c["estimates"]["incidence_noise_exponent"].get<double>();
      EXPECT_GT(g, 0.3) << "seed " << seed << ", gamma " << gamma;
      EXPECT_LT(g, gamma + 0.2) << "seed " << seed << ", gamma " << gamma;
    }
}

TEST(CliDiagnoseDriving, ALidarYawedOnARobotThatNeverStopsIsNamedFromItsOdometrySteps) {
  // A lidar mounted 2.5-3.5 degrees off the robot's axis, on a robot that never stops among thin
  // poles. Each scan's heading is refined, so the readings alone cannot tell the offset from the
  // headings; the odometry steps can: the robot drives along its own axis, which the yawed lidar
  // sees turned. Started from the baseline's headings, with its baseline refitted with the offset
  // dropped from the beams and no step held out, such drives were named none in 5 of 5. The
  // offset's size and sign and the simulator's seed come from a seed this test does not read. Sizes
  // from 2.5 degrees, 4.5 standard errors of this drive's 0.55: at 2.07 degrees (3.8 standard
  // errors) one drive was reported none, the offset estimated at 1.95 but Holm's p 0.011 against
  // 0.01, the detection limit (docs/results/hidden-effects.md).
  TempDir dir;
  auto rng = makeRng(20261127, 23);
  const double sign = std::bernoulli_distribution(0.5)(rng) ? 1.0 : -1.0;
  const double yaw_deg = sign * std::uniform_real_distribution<double>(2.5, 3.5)(rng);
  const int seed = std::uniform_int_distribution<int>(100, 100000)(rng);
  const auto r = diagnoseThinPoleDrive(
      dir.path(), [&](nlohmann::json& s) { s["sensor"]["mount_yaw_deg"] = yaw_deg; }, seed);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "angle_offset\n") << "seed " << seed << ", yaw " << yaw_deg << " deg";
  const auto j = json(dir / "d/diagnosis.json");
  for (const auto& c : j["candidates"])
    if (c["effect"] == "angle_offset") {
      // Its standard error is what the odometry steps know of it (the headings a nuisance):
      // about a third of a degree on this drive with the odometry's noise fitted from its steps
      // (half a degree at the prior's defaults), not the readings' 0.06 degrees.
      const double se_deg = c["standard_error"].get<double>() * 180.0 / std::acos(-1.0);
      EXPECT_GT(se_deg, 0.1);
      EXPECT_LT(se_deg, 1.0);
      EXPECT_NEAR(c["estimates"]["angle_offset_deg"].get<double>(), yaw_deg, 3.0 * se_deg)
          << "seed " << seed;
      EXPECT_FALSE(c["p_likelihood_ratio"].is_null());
      EXPECT_GT(c["heldout_gain_nats_per_point"].get<double>(), 0.0);
    }
  // Every significant term in the mean fits all the data better than the baseline: one that did
  // not (a drift of 0.26 mm over such a drive, 1.2 nats less likely than the baseline) had
  // outgained the offset through its folds' other optima.
  expectInSampleEvidence(j, "seed " + std::to_string(seed));
}

TEST(CliDiagnoseDriving, TheOdometrysNoiseIsFittedFromTheDrivesOwnSteps) {
  // A robot's odometry is unknown to diagnose: the motion prior's standard deviations are scaled
  // by what the drive's own steps show. The simulator draws each step's coordinates with a
  // standard deviation of translation_fraction times the step, its heading change with
  // heading_deg_per_m times the step (no turn-proportional part here); both, and the seed, come
  // from a seed this test does not read, below the prior's defaults (5 mm and 5 mrad on a 3 cm
  // step), which are the loosest the fitted prior gets. The fitted standard deviations of a 3 cm
  // step must match the simulator's within four of their standard errors (about 5-7 % each).
  TempDir dir;
  auto rng = makeRng(20261128, 31);
  const double fraction = std::uniform_real_distribution<double>(0.04, 0.14)(rng);
  const double heading_deg_per_m = std::uniform_real_distribution<double>(2.0, 8.0)(rng);
  const int seed = std::uniform_int_distribution<int>(100, 100000)(rng);
  const auto r = diagnoseThinPoleDrive(
      dir.path(),
      [&](nlohmann::json& s) {
        s["path"]["odometry"] = {{"translation_fraction", fraction},
                                 {"heading_deg_per_m", heading_deg_per_m},
                                 {"heading_fraction", 0.0}};
      },
      seed);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto f = json(dir / "d/diagnosis.json")["baseline"]["fitted"];
  ASSERT_EQ(f["odometry_noise_fitted"], 1.0) << "leverage " << f["odometry_step_leverage"];
  const double step = 0.03;  // the scene's speed per scan; the odometry's steps scatter about it
  EXPECT_NEAR(f["odometry_step_m"].get<double>(), step, 0.1 * step);
  const std::string what = "seed " + std::to_string(seed) + ", fraction " +
                           std::to_string(fraction) + ", heading " +
                           std::to_string(heading_deg_per_m) + " deg/m";
  const double want_t = fraction * step, got_t = f["odometry_step_sd_m"].get<double>();
  const double se_t = got_t * f["odometry_translation_factor_se"].get<double>() /
                      f["odometry_translation_factor"].get<double>();
  EXPECT_GT(se_t, 0.0);
  EXPECT_NEAR(got_t, want_t, 4.0 * se_t) << what;
  const double want_h = heading_deg_per_m * std::acos(-1.0) / 180.0 * step,
               got_h = f["odometry_step_heading_sd_rad"].get<double>();
  const double se_h = got_h * f["odometry_heading_factor_se"].get<double>() /
                      f["odometry_heading_factor"].get<double>();
  EXPECT_GT(se_h, 0.0);
  EXPECT_NEAR(got_h, want_h, 4.0 * se_h) << what;
}

TEST(CliDiagnoseDriving, ANoiseLawFlatterThanTheSquaredOneIsNamedOnThinPolesAtTheDefaultReplicas) {
  // The noise grows as f(d)^k, k 0.5-1, instead of Alhashimi et al. 2016's f(d)^2, its scale
  // matched to the squared law's at f(d) = 1.8 m, near where this drive sees its poles: the two
  // laws part only at its nearest and farthest readings. With 5 bootstrap replicas 4 of 20 such
  // drives were named none (the statistic's p from a Student t of 4 degrees of freedom); with
  // diagnose's default of 19, 1 of 20 (docs/results/hidden-effects.md). The exponent and the
  // simulator's seed come from a seed this test does not read.
  TempDir dir;
  auto rng = makeRng(20261128, 37);
  const double k = std::uniform_real_distribution<double>(0.5, 1.0)(rng);
  const int seed = std::uniform_int_distribution<int>(100, 100000)(rng);
  const auto r = diagnoseThinPoleDrive(
      dir.path(),
      [&](nlohmann::json& s) {
        const double sigma = s["sensor"]["noise"]["sigma_e"].get<double>() * std::pow(1.8, 2.0 - k);
        s["sensor"]["noise"] = {{"kind", "power"}, {"sigma_e", sigma}, {"exponent", k}};
      },
      seed, 19);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "range_noise_law\n") << "seed " << seed << ", k " << k;
  const auto j = json(dir / "d/diagnosis.json");
  for (const auto& c : j["candidates"])
    if (c["effect"] == "range_noise_law") {
      // Fitted near its size (0.97-1.19 for k 0.95-0.97 in the drives of
      // docs/results/hidden-effects.md), and clear of the squared law.
      const double kappa = c["estimates"]["noise_exponent"].get<double>();
      EXPECT_NEAR(kappa, k, 0.5) << "seed " << seed;
      EXPECT_LT(kappa, 1.7) << "seed " << seed << ", k " << k;
    }
}

}  // namespace
}  // namespace lidarcal
