// SPDX-License-Identifier: BSD-3-Clause
// The joint fit of odometry, mounting and range bias against its Cramer-Rao bound on simulated
// drives (docs/results/odometry.md): per parameter the fit's mean error, its mean squared error,
// the bound (the inverse Fisher information at the truth, with poses and poles eliminated), the
// efficiency bound / MSE and how often the 95 % interval holds the truth; then the same drives
// fitted as Censi et al. 2013 do, the range held exact, and how much each bound grows when the
// range offset is unknown.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "common/pose2.hpp"
#include "io/landmarks_csv.hpp"
#include "io/sequence.hpp"
#include "io/wheel_angles_csv.hpp"
#include "odometry/drive_fit.hpp"
#include "odometry/simulated_drive.hpp"

namespace {

using lidarcal::odometry::DriveFitSetup;
using lidarcal::odometry::DriveSimulation;
using lidarcal::odometry::EstimatedSet;
using lidarcal::odometry::kDriveParameterCount;
using lidarcal::odometry::kDriveParameterNames;
using lidarcal::odometry::Vector8;

/// What one way of fitting gave over the seeds, per parameter.
struct Tally {
  Vector8 error_sum = Vector8::Zero();
  Vector8 squared_sum = Vector8::Zero();
  Vector8 bound_sum = Vector8::Zero();  ///< the bound's variance, summed over the seeds
  Eigen::Matrix<int, kDriveParameterCount, 1> covered = decltype(covered)::Zero();
  int fits = 0;
  int failed = 0;

  void add(const Vector8& error, const Vector8& se, const Vector8& bound_variance) {
    ++fits;
    error_sum += error;
    squared_sum += error.cwiseAbs2();
    bound_sum += bound_variance;
    for (int i = 0; i < kDriveParameterCount; ++i)
      if (std::abs(error[i]) <= 1.959964 * se[i]) ++covered[i];
  }
};

/// Fits one drive with `estimated` and adds it to `tally`; the range offset held at 0 when not
/// estimated (a perfect range, as Censi et al. 2013 assume).
void fitOne(const lidarcal::odometry::SimulatedDrive& drive, const DriveSimulation& sim,
            const EstimatedSet& estimated, Tally& tally) {
  DriveFitSetup setup;
  setup.initial = {sim.nominal, 0.0, 0.0};
  setup.estimated = estimated;
  setup.noise = sim.noise;
  const auto fit = lidarcal::odometry::fitDrive(drive.record, setup);
  if (!fit.ok()) {
    ++tally.failed;
    return;
  }
  const auto bound = lidarcal::odometry::driveInformation(drive.record, drive.truth, setup);
  tally.add(fit.state.params.toVector() - drive.truth.params.toVector(), fit.standardErrors(),
            bound.covariance.diagonal());
}

nlohmann::json report(const Tally& t, const EstimatedSet& estimated) {
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < kDriveParameterCount; ++i) {
    if (!estimated[i] || t.fits == 0) continue;
    const double mse = t.squared_sum[i] / t.fits;
    const double bound = t.bound_sum[i] / t.fits;
    rows.push_back({{"parameter", kDriveParameterNames[i]},
                    {"mean_error", t.error_sum[i] / t.fits},
                    {"rmse", std::sqrt(mse)},
                    {"bound_sd", std::sqrt(bound)},
                    {"efficiency", bound / mse},
                    {"coverage_95", static_cast<double>(t.covered[i]) / t.fits}});
  }
  return {{"fits", t.fits}, {"failed", t.failed}, {"parameters", rows}};
}

void print(const char* title, const nlohmann::json& r) {
  std::printf("\n%s: %d fits, %d failed\n", title, r["fits"].get<int>(), r["failed"].get<int>());
  std::printf("%-16s %12s %12s %12s %10s %9s\n", "parameter", "mean error", "RMSE", "bound SD",
              "efficiency", "coverage");
  for (const auto& row : r["parameters"])
    std::printf("%-16s %12.3e %12.3e %12.3e %10.3f %9.3f\n",
                row["parameter"].get<std::string>().c_str(), row["mean_error"].get<double>(),
                row["rmse"].get<double>(), row["bound_sd"].get<double>(),
                row["efficiency"].get<double>(), row["coverage_95"].get<double>());
}

/// Writes `drive` as `lidarcal odometry-drive` reads it: DIR/wheel_angles.csv and
/// DIR/landmarks.csv (as `lidarcal detect --radius R` writes it; one pole per landmark id).
void writeExample(const lidarcal::odometry::SimulatedDrive& drive, const std::string& dir) {
  std::filesystem::create_directories(dir);
  const auto name = lidarcal::io::scanFileName;
  std::vector<lidarcal::io::WheelAngleRow> wheels{{name(0), 0.0, 0.0}};
  for (const auto& step : drive.record.steps)
    wheels.push_back({name(wheels.size()), wheels.back().left_rad + step.left_rad,
                      wheels.back().right_rad + step.right_rad});
  lidarcal::io::writeWheelAnglesCsv(dir + "/wheel_angles.csv", wheels);
  lidarcal::io::LandmarksCsvWriter out(dir + "/landmarks.csv");
  const double radius = drive.record.pole_radius_m;
  for (const auto& s : drive.record.sightings) {
    const double range = s.range_m + radius;
    out.write({name(s.scan), s.scan, s.pole + 1, s.bearing_rad, range,
               range * std::cos(s.bearing_rad), range * std::sin(s.bearing_rad), radius, 12, 0.0});
  }
  out.close();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The joint odometry, mounting and range fit against its Cramer-Rao bound"};
  int seeds = 500;
  std::uint64_t first_seed = 1;
  DriveSimulation sim;
  std::string json_path;
  app.add_option("--seeds", seeds, "simulated drives")->check(CLI::PositiveNumber);
  app.add_option("--first-seed", first_seed, "seed of the first drive");
  app.add_option("--laps", sim.laps, "times each drive goes round")->check(CLI::PositiveNumber);
  double fov_deg = 360.0;
  app.add_option("--fov", fov_deg, "the laser's field of view, degrees")
      ->check(CLI::Range(10.0, 360.0));
  app.add_option("--bearing-sigma", sim.noise.bearing_sigma_rad, "bearing noise, radians")
      ->capture_default_str();
  app.add_option("--range-sigma", sim.noise.range_sigma_m, "range noise, metres")
      ->capture_default_str();
  double beam_step_deg = 0.0;
  app.add_option("--beam-step", beam_step_deg,
                 "> 0: fit the beams one every this many degrees hit (those odometry-drive "
                 "--beams keeps), with --range-sigma per beam")
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--json", json_path, "write the tables here as JSON");
  std::string example;
  app.add_option("--write-example", example,
                 "write the first drive to DIR as odometry-drive's input, and stop");
  CLI11_PARSE(app, argc, argv);
  sim.field_of_view_rad = fov_deg * lidarcal::kPi / 180.0;
  sim.beam_step_rad = beam_step_deg * lidarcal::kPi / 180.0;
  if (!example.empty()) {
    sim.seed = first_seed;
    writeExample(lidarcal::odometry::simulateDrive(sim), example);
    return 0;
  }

  const EstimatedSet joint = lidarcal::odometry::kEstimateAllButScale;
  const EstimatedSet exact_range = {true, true, true, true, true, true, false, false};
  Tally joint_tally, exact_tally;
  for (int s = 0; s < seeds; ++s) {
    sim.seed = first_seed + static_cast<std::uint64_t>(s);
    auto drive = lidarcal::odometry::simulateDrive(sim);
    if (sim.beam_step_rad > 0.0)
      drive.record =
          lidarcal::odometry::centralBeams(drive.record, lidarcal::odometry::kCentralFraction);
    fitOne(drive, sim, joint, joint_tally);
    fitOne(drive, sim, exact_range, exact_tally);
    if ((s + 1) % 50 == 0) std::fprintf(stderr, "%d of %d drives\n", s + 1, seeds);
  }
  nlohmann::json out = {{"seeds", seeds},
                        {"first_seed", first_seed},
                        {"laps", sim.laps},
                        {"field_of_view_deg", fov_deg},
                        {"bearing_sigma_rad", sim.noise.bearing_sigma_rad},
                        {"range_sigma_m", sim.noise.range_sigma_m},
                        {"beam_step_deg", beam_step_deg},
                        {"joint", report(joint_tally, joint)},
                        {"range_held_exact", report(exact_tally, exact_range)}};
  print("joint fit (range offset estimated)", out["joint"]);
  print("range held exact (Censi et al. 2013's assumption)", out["range_held_exact"]);
  if (!json_path.empty()) std::ofstream(json_path) << out.dump(2) << '\n';
  return 0;
}
