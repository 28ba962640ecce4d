// SPDX-License-Identifier: BSD-3-Clause
// rig_coverage: do the standard errors of calibrateRig hold the simulated truth as often as
// they claim? For each scenario (two or three lidars; stop and go, driving, static), each seed
// draws a vehicle (tests/calibration/rig_scenes.hpp), calibrates it and records, per estimated
// quantity, the error against the truth over its standard error. Prints one Markdown table: the
// RMS error, the mean standard error, the mean error over its SE (a bias shows as a mean away
// from 0 by more than about 2 / sqrt(seeds)), the fraction of |error| <= 1.96 SE (target 95 %:
// 90-97 % over 50 seeds) and the largest |error| / SE, then the same fraction over every quantity
// of the scenario (docs/results/several-lidars.md).
//
//   rig_coverage [--seeds 50] [--first 1] [--scenarios two-stops,two-driving,...]
//   [--lateral-fraction 0.7]

#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "calibration/rig_calibrate.hpp"
#include "calibration/rig_scenes.hpp"

namespace {

using namespace lidarcal;

struct Tally {
  double sq = 0.0, se = 0.0, worst = 0.0, z_sum = 0.0;
  int n = 0, inside = 0, worst_seed = 0;
  void add(double error, double se_value, int seed) {
    const double z = std::abs(error) / se_value;
    z_sum += error / se_value;
    sq += error * error;
    se += se_value;
    if (z > worst) worst = z, worst_seed = seed;
    inside += z <= 1.96;
    ++n;
  }
};

struct Scenario {
  std::string name;
  simulation::RigSimConfig sim;
  calibration::RigConfig config;
};

Scenario scenario(const std::string& name, double lateral_fraction) {
  const bool three = name.rfind("three", 0) == 0;
  Scenario s{name, {}, {}};
  if (name.find("driving") != std::string::npos) {
    s.sim = test::driving(three);
    const auto& odo = s.sim.driving.driving.odometry;
    s.config.motion_sigma_fraction = odo.translation_fraction;
    s.config.motion_sigma_floor_m = 1e-4;
    s.config.motion_heading_sigma_rad_per_m = odo.heading_rad_per_m;
    s.config.motion_heading_floor_rad = 1e-4;
  } else if (name.find("static") != std::string::npos) {
    s.sim = test::staticVehicle(three);
  } else {
    s.sim = test::stopAndGo(three);
    s.config.sigma_vehicle_m = s.sim.sigma_s_m;
    s.config.sigma_vehicle_rad = s.sim.sigma_psi_rad;
  }
  s.config.lateral_fraction = lateral_fraction;
  // the truth's order: the coverage of the SEs, not the order choice
  s.config.orders.assign(s.sim.sensors.size(), 1);
  return s;
}

void run(const Scenario& sc, int first, int seeds) {
  std::map<std::string, Tally> tallies;
  int failed = 0;
  for (int seed = first; seed < first + seeds; ++seed) {
    const simulation::RigSimSample sample =
        simulation::simulateRig(sc.sim, static_cast<std::uint64_t>(seed));
    const calibration::RigResult r = calibration::calibrateRig(sample.obs, sc.config);
    if (!r.ok()) {
      ++failed;
      continue;
    }
    for (std::size_t s = 0; s < r.sensors.size(); ++s) {
      const auto& e = r.sensors[s];
      const auto& truth = sc.sim.sensors[s];
      const std::string who = truth.name + " ";
      if (r.frame == calibration::RigFrame::vehicle) {
        tallies[who + "x"].add(e.mounting.x_m - truth.mounting.x_m,
                               std::sqrt(e.mounting_covariance(0, 0)), seed);
        tallies[who + "y"].add(e.mounting.y_m - truth.mounting.y_m,
                               std::sqrt(e.mounting_covariance(1, 1)), seed);
        tallies[who + "yaw"].add(wrapAngle(e.mounting.yaw_rad - truth.mounting.yaw_rad),
                                 std::sqrt(e.mounting_covariance(2, 2)), seed);
      }
      if (!e.scale_held) {
        // Relative scales when the common one is a gauge: alpha_1 over the reference's true
        // alpha_1.
        const double scale = r.scale_free ? sc.sim.sensors[r.reference].model.bias.alpha[1] : 1.0;
        tallies[who + "alpha_1"].add(e.model.bias.alpha[1] - truth.model.bias.alpha[1] / scale,
                                     std::sqrt(e.alpha_covariance(1, 1)), seed);
        if (!r.scale_free)
          tallies[who + "alpha_0"].add(e.model.bias.alpha[0] - truth.model.bias.alpha[0],
                                       std::sqrt(e.alpha_covariance(0, 0)), seed);
      }
    }
    for (const auto& rel : r.relative) {
      const Pose2 t = relativeMounting(sc.sim.sensors[rel.reference].mounting,
                                       sc.sim.sensors[rel.sensor].mounting);
      // geometry in the reference's units
      const double scale = r.scale_free ? sc.sim.sensors[r.reference].model.bias.alpha[1] : 1.0;
      const std::string who =
          sc.sim.sensors[rel.sensor].name + " from " + sc.sim.sensors[rel.reference].name + " ";
      tallies[who + "x"].add(rel.pose.x_m - t.x_m * scale, std::sqrt(rel.covariance(0, 0)), seed);
      tallies[who + "y"].add(rel.pose.y_m - t.y_m * scale, std::sqrt(rel.covariance(1, 1)), seed);
      tallies[who + "yaw"].add(wrapAngle(rel.pose.yaw_rad - t.yaw_rad),
                               std::sqrt(rel.covariance(2, 2)), seed);
    }
  }
  for (const auto& [name, t] : tallies) {
    const bool angle = name.size() >= 3 && name.compare(name.size() - 3, 3, "yaw") == 0;
    const double unit = angle ? 180.0 / kPi : 1000.0;
    std::printf("| %s | %s | %d | %.3g | %.3g | %+.2f | %.1f %% | %.2f (seed %d) |\n",
                sc.name.c_str(), name.c_str(), t.n, unit * std::sqrt(t.sq / t.n), unit * t.se / t.n,
                t.z_sum / t.n, 100.0 * t.inside / t.n, t.worst, t.worst_seed);
  }
  // Every quantity of every seed pooled: one coverage per scenario (the quantities of one seed are
  // correlated, so it spreads more than a binomial over their count would).
  int all = 0, inside = 0;
  for (const auto& [name, t] : tallies) all += t.n, inside += t.inside;
  if (all)
    std::printf("| %s | every quantity | %d | | | | %.1f %% | |\n", sc.name.c_str(), all,
                100.0 * inside / all);
  if (failed)
    std::printf("| %s | calibrations refused | %d | | | | | |\n", sc.name.c_str(), failed);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Coverage of the rig calibration's standard errors over simulated seeds"};
  int seeds = 50, first = 1;
  std::vector<std::string> names{"two-stops",     "two-driving", "three-stops",
                                 "three-driving", "two-static",  "three-static"};
  app.add_option("--seeds", seeds, "Seeds per scenario")->capture_default_str();
  app.add_option("--first", first, "First seed")->capture_default_str();
  app.add_option("--scenarios", names, "Scenarios")->delimiter(',');
  double lateral = calibration::RigConfig{}.lateral_fraction;
  app.add_option("--lateral-fraction", lateral,
                 "Beams passing within this fraction of a pole's radius from its centre are fitted")
      ->check(CLI::Range(0.05, 1.0))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::printf(
      "| scenario | quantity | fits | RMS error (mm, deg, 1e-3) | mean SE | mean error/SE | within "
      "1.96 SE | max error/SE (seed) |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const std::string& n : names) run(scenario(n, lateral), first, seeds);
  return 0;
}
