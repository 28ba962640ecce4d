// SPDX-License-Identifier: BSD-3-Clause
// lidarcal odometry-drive --wheels wheel_angles.csv --landmarks landmarks.csv --nominal ... -o OUT
// Calibrates a differential-drive robot's wheel radii and axle, its laser's mounting and the
// laser's range offset in one maximum-likelihood fit over a drive among poles, every pose and
// pole estimated with them (odometry/drive_fit.hpp); prints each estimate with its standard error
// and writes OUT.json (docs/FORMAT.md, "lidarcal-odometry-drive/1").

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "common/number_text.hpp"
#include "common/plural.hpp"
#include "common/pose2.hpp"
#include "io/atomic_file.hpp"
#include "io/json_number.hpp"
#include "io/landmarks_csv.hpp"
#include "io/pcd_scan.hpp"
#include "io/wheel_angles_csv.hpp"
#include "odometry/drive_fit.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/covariance_json.hpp"
#include "pipeline/reports/papers.hpp"
#include "pipeline/reports/shown_parameter.hpp"

namespace lidarcal::pipeline {
namespace {

struct DriveOptions {
  std::string wheels, landmarks, out;
  std::vector<double> nominal;
  std::vector<std::string> hold;
  bool estimate_range_scale = false;
  bool beams = false;
  odometry::DriveNoise noise;
  bool overwrite = false;
};

constexpr ShownParameter kShown[odometry::kDriveParameterCount] = {
    {"left wheel radius r_L", "mm", 1e3},
    {"right wheel radius r_R", "mm", 1e3},
    {"axle b", "mm", 1e3},
    {"laser x l_x", "mm", 1e3},
    {"laser y l_y", "mm", 1e3},
    {"laser heading l_theta", "deg", 180.0 / kPi},
    {"range offset a_0", "mm", 1e3},
    {"range scale a_1", "%", 100.0}};

/// Every labelled return of the scans `detect` wrote beside landmarks.csv, as a beam of the
/// scan of its file on the pole of its label.
void addBeams(const DriveOptions& o, const std::vector<io::LandmarkRow>& rows,
              const std::map<std::string, std::size_t>& scan_of, odometry::DriveRecord& record) {
  const std::filesystem::path dir = std::filesystem::path(o.landmarks).parent_path();
  std::set<std::string> read;
  Progress progress("reading labelled scans", scan_of.size(), !quiet());
  for (const io::LandmarkRow& r : rows) {
    if (!read.insert(r.file).second) continue;
    progress.update(read.size());
    const std::filesystem::path file = dir / r.file;
    if (!std::filesystem::exists(file))
      throw InputError(file.string(), "file", "the labelled scan is missing",
                       "give --landmarks the landmarks.csv of `lidarcal detect --out DIR`, in DIR "
                       "beside the labelled scans, or leave out --beams");
    const io::Scan scan = io::readScan(file);
    if (scan.labels.empty())
      throw InputError(file.string(), "label", "the scan has no label field",
                       "give --landmarks the landmarks.csv of `lidarcal detect`, in the directory "
                       "of its labelled scans");
    for (std::size_t i = 0; i < scan.labels.size(); ++i) {
      const double x = scan.cloud->points[i].x, y = scan.cloud->points[i].y;
      if (scan.labels[i] == 0 || !std::isfinite(x) || !std::isfinite(y)) continue;
      record.beams.push_back({scan_of.at(r.file), static_cast<int>(scan.labels[i]),
                              std::atan2(y, x), std::hypot(x, y)});
    }
  }
  progress.finish();
}

/// The drive as the fit sees it: steps between consecutive rows of the wheel angles, each
/// landmark row as a sighting of the scan of its file, and with --beams the labelled returns.
odometry::DriveRecord driveRecord(const DriveOptions& o) {
  const std::vector<io::WheelAngleRow> wheels = io::readWheelAnglesCsv(o.wheels);
  const std::vector<io::LandmarkRow> rows = io::readLandmarksCsv(o.landmarks);
  odometry::DriveRecord record;
  std::map<std::string, std::size_t> scan_of;
  for (std::size_t k = 0; k < wheels.size(); ++k) {
    scan_of[wheels[k].file] = k;
    if (k > 0)
      record.steps.push_back({wheels[k].left_rad - wheels[k - 1].left_rad,
                              wheels[k].right_rad - wheels[k - 1].right_rad});
  }
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const io::LandmarkRow& r = rows[i];
    const auto it = scan_of.find(r.file);
    if (it == scan_of.end())
      throw InputError(o.landmarks, "row " + std::to_string(i + 1) + ", column file",
                       "scan `" + r.file + "` has no row in " + o.wheels,
                       "give the wheels' angles at every scan that sees a pole");
    if (i > 0 && r.radius_m != rows.front().radius_m)
      throw InputError(o.landmarks, "row " + std::to_string(i + 1) + ", column radius_m",
                       "the poles' radius differs between rows",
                       "measure the poles and run `lidarcal detect --radius R`: the joint fit "
                       "needs the radius known");
    record.sightings.push_back({it->second, r.landmark, r.range_m - r.radius_m, r.bearing_rad});
  }
  if (!rows.empty()) record.pole_radius_m = rows.front().radius_m;
  if (!o.beams) return record;
  addBeams(o, rows, scan_of, record);
  return odometry::centralBeams(record, odometry::kCentralFraction);
}

odometry::DriveFitSetup fitSetup(const DriveOptions& o) {
  odometry::DriveFitSetup setup;
  odometry::Vector8 initial = odometry::Vector8::Zero();
  for (std::size_t i = 0; i < o.nominal.size(); ++i) initial[static_cast<int>(i)] = o.nominal[i];
  setup.initial = odometry::DriveParameters::fromVector(initial);
  setup.estimated = odometry::kEstimateAllButScale;
  setup.estimated[7] = o.estimate_range_scale;
  for (const std::string& name : o.hold)
    for (int i = 0; i < odometry::kDriveParameterCount; ++i)
      if (name == odometry::kDriveParameterNames[i]) setup.estimated[i] = false;
  setup.noise = o.noise;
  return setup;
}

std::string combinationText(const odometry::Vector8& d) {
  std::string text;
  for (int i = 0; i < odometry::kDriveParameterCount; ++i) {
    if (std::abs(d[i]) < 1e-9) continue;  // held, or not in the combination
    text +=
        formatted("%s%.3g %s", text.empty() ? "" : " + ", d[i], odometry::kDriveParameterNames[i]);
  }
  return text;
}

nlohmann::json outputJson(const DriveOptions& o, const odometry::DriveRecord& record,
                          const odometry::DriveFitSetup& setup, const odometry::DriveFit& fit,
                          const odometry::VarianceByKind& by_kind) {
  nlohmann::json j;
  j["format"] = "lidarcal-odometry-drive/1";
  j["input"] = {{"wheels", o.wheels}, {"landmarks", o.landmarks}};
  j["method"] =
      "joint maximum likelihood over every pose and pole; covariance: the inverse "
      "Fisher information with poses and poles eliminated, times the variance factor";
  j["noise"] = {{"range_sigma_m", o.noise.range_sigma_m},
                {"bearing_sigma_rad", o.noise.bearing_sigma_rad},
                {"slip_m_per_sqrt_m", o.noise.slip_m_per_sqrt_m},
                {"slip_rad_per_sqrt_rad", o.noise.slip_rad_per_sqrt_rad}};
  j["drive"] = {{"scans", record.scans()},
                {"sightings", record.sightings.size()},
                {"pole_radius_m", record.pole_radius_m}};
  if (record.byBeam()) j["drive"]["beams"] = record.beams.size();
  j["status"] = {{"code", fit.status.name()}, {"message", fit.status.message}};
  const odometry::Vector8 value = fit.state.params.toVector(), se = fit.scaledStandardErrors(),
                          stated = fit.standardErrors();
  nlohmann::json estimate, error, error_stated, held = nlohmann::json::array();
  for (int i = 0; i < odometry::kDriveParameterCount; ++i) {
    const char* name = odometry::kDriveParameterNames[i];
    estimate[name] = value[i];
    error[name] = setup.estimated[i] ? nlohmann::json(se[i]) : nullptr;
    error_stated[name] = setup.estimated[i] ? nlohmann::json(stated[i]) : nullptr;
    if (!setup.estimated[i]) held.push_back(name);
  }
  j["estimate"] = estimate;
  j["standard_error"] = error;
  j["standard_error_stated_noise"] = error_stated;
  j["held"] = held;
  j["covariance"] = covarianceJson(odometry::kDriveParameterNames,
                                   fit.information.covariance * fit.variance_factor);
  j["variance_factor"] = fit.variance_factor;
  nlohmann::json kinds;
  const char* names[] = {"odometry_translation", "odometry_heading", "range", "bearing"};
  for (int k = 0; k < 4; ++k)
    kinds[names[k]] = {{"variance_factor", io::jsonNumber<nlohmann::json>(by_kind.factor[k])},
                       {"redundancy", by_kind.redundancy[k]}};
  j["by_kind"] = kinds;
  return j;
}

void printResult(const odometry::DriveRecord& record, const odometry::DriveFitSetup& setup,
                 const odometry::DriveFit& fit, const odometry::VarianceByKind& by_kind) {
  const std::string seen = record.byBeam() ? plural(record.beams.size(), "beam") + " on " +
                                                 plural(record.sightings.size(), "pole sighting")
                                           : plural(record.sightings.size(), "pole sighting");
  std::printf("odometry, mounting and range from a drive of %s and %s (%s)\n\n",
              plural(record.scans(), "scan").c_str(), seen.c_str(),
              fit.iterations > 0 ? "joint maximum likelihood" : "not fitted");
  std::printf("| parameter | estimate | standard error | unit |\n|---|---|---|---|\n");
  const odometry::Vector8 value = fit.state.params.toVector(), se = fit.scaledStandardErrors();
  for (int k = 0; k < odometry::kDriveParameterCount; ++k) {
    const double s = kShown[k].scale;
    if (setup.estimated[k])
      std::printf("| %s | %.3f | %.3f | %s |\n", kShown[k].label, value[k] * s, se[k] * s,
                  kShown[k].unit);
    else
      std::printf("| %s | %.3f | held | %s |\n", kShown[k].label, value[k] * s, kShown[k].unit);
  }
  std::printf(
      "\nvariance factor %.3f: the residuals over the stated noise (near 1 when it is right; the "
      "standard errors above include it)\nby kind: odometry %.2f (translation), %.2f (heading); "
      "range%s %.2f; bearing %.2f\n",
      fit.variance_factor, by_kind.factor[0], by_kind.factor[1], record.byBeam() ? " (beams)" : "",
      by_kind.factor[2], by_kind.factor[3]);
}

void runOdometryDrive(const DriveOptions& o) {
  for (const std::string& in : {o.wheels, o.landmarks}) io::checkOutsideInput(in, o.out);
  io::checkOutputFile(o.out, o.overwrite);
  const odometry::DriveRecord record = driveRecord(o);
  const odometry::DriveFitSetup setup = fitSetup(o);
  const odometry::DriveFit fit = odometry::fitDrive(record, setup);
  if (!fit.ok()) {
    std::string what = fit.status.message;
    for (const odometry::Vector8& d : fit.information.inseparable)
      what += "; undetermined: " + combinationText(d);
    throw DataError(o.landmarks, "calibration", std::string(fit.status.name()) + ": " + what,
                    "hold a parameter you have measured (--hold NAME), or record a drive with "
                    "turns in place, curves both ways and straight lines among at least three "
                    "poles");
  }
  const odometry::VarianceByKind by_kind = odometry::varianceByKind(record, setup, fit);
  io::writeTextAtomically(o.out, outputJson(o, record, setup, fit, by_kind).dump(2) + "\n");
  printResult(record, setup, fit, by_kind);
  if (!quiet()) std::fprintf(stderr, "odometry-drive calibration written to %s\n", o.out.c_str());
}

}  // namespace

void addOdometryDriveCommand(CLI::App& app) {
  auto o = std::make_shared<DriveOptions>();
  CLI::App* sub = app.add_subcommand(
      "odometry-drive",
      "Calibrate wheel radii, axle, the laser's mounting and its range offset in one fit over a "
      "drive among poles");
  sub->add_option("--wheels", o->wheels,
                  "wheel_angles.csv: each wheel's cumulative angle at each scan (docs/FORMAT.md)")
      ->required();
  sub->add_option("--landmarks", o->landmarks,
                  "landmarks.csv of `lidarcal detect --radius R` on the same scans")
      ->required();
  sub->add_option("--nominal", o->nominal,
                  "Starting values: r_L,r_R,b,l_x,l_y,l_theta (metres, radians), e.g. the "
                  "maker's figures")
      ->delimiter(',')
      ->expected(6)
      ->required();
  sub->add_option("--hold", o->hold, "Parameters held at their --nominal value (names as in OUT)")
      ->delimiter(',')
      ->check(CLI::IsMember(std::vector<std::string>(odometry::kDriveParameterNames.begin(),
                                                     odometry::kDriveParameterNames.end())));
  sub->add_flag("--beams", o->beams,
                "Fit every labelled return of the scans beside --landmarks (detect's output) "
                "in place of each detection's range: no error from circles fitted through "
                "returns that the range bias moved along their beams; --range-sigma is then one "
                "beam's noise");
  sub->add_flag("--estimate-range-scale", o->estimate_range_scale,
                "Also fit a range scale a_1 (with free wheel radii it cannot be told from a common "
                "scale of the robot: hold the radii or the axle)");
  sub->add_option("--range-sigma", o->noise.range_sigma_m, "Range noise, metres")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--bearing-sigma", o->noise.bearing_sigma_rad, "Bearing noise, radians")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--slip", o->noise.slip_m_per_sqrt_m,
                  "Odometry translation error per square root of metres driven")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--slip-turn", o->noise.slip_rad_per_sqrt_rad,
                  "Odometry heading error per square root of radians turned")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("-o,--out", o->out, "Result file OUT.json (lidarcal-odometry-drive/1)")
      ->required();
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT.json if it exists");
  sub->footer(std::string("Without --hold the range offset is estimated with the odometry and "
                          "the mounting; --hold range_offset_m gives the assumption of an exact "
                          "range (") +
              papers::kOdometry + "). Exit 3 when the drive cannot determine the parameters.");
  sub->callback([o] { runOdometryDrive(*o); });
}

}  // namespace lidarcal::pipeline
