// SPDX-License-Identifier: BSD-3-Clause
// lidarcal odometry TUPLES -o OUT.json [--subsets N [--subset-split consecutive|interleaved]]
//   [--rounds R] [--percentile P]
// Calibrates a differential-drive robot's wheel radii and axle and its laser's mounting from
// odometry tuples (Censi et al. 2013); prints the six parameters with their standard errors and
// writes OUT.json (docs/FORMAT.md, "lidarcal-odometry/1"). With --subsets, also how the
// estimates of N consecutive subsets scatter beside their stated standard errors.

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "common/plural.hpp"
#include "common/pose2.hpp"
#include "io/atomic_file.hpp"
#include "io/odometry_tuples.hpp"
#include "odometry/calibrate.hpp"
#include "odometry/subsets.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/covariance_json.hpp"
#include "pipeline/reports/papers.hpp"
#include "pipeline/reports/shown_parameter.hpp"

namespace lidarcal::pipeline {
namespace {

struct OdometryOptions {
  std::string tuples, out;
  int subsets = 0;  // 0: no subset scatter
  std::string split = "consecutive";
  odometry::OdometrySettings settings;
  bool overwrite = false;
};

constexpr ShownParameter kShown[odometry::kParameterCount] = {
    {"left wheel radius r_L", "mm", 1e3},
    {"right wheel radius r_R", "mm", 1e3},
    {"axle b", "mm", 1e3},
    {"laser x l_x", "mm", 1e3},
    {"laser y l_y", "mm", 1e3},
    {"laser heading l_theta", "deg", 180.0 / kPi}};

/// What to record when the data cannot determine the parameters.
std::string whatToRecord(StatusCode code) {
  switch (code) {
    case StatusCode::negative_axle:
      return "check the wheels in the tuples: phi_l must be the left wheel and phi_r the right, "
             "both positive when the robot drives forward";
    case StatusCode::too_few_samples:
      return "record longer: minutes of driving (hundreds of intervals) with turns in both "
             "directions and some curved or straight driving";
    default:
      return "record turns in both directions (in place or about one wheel) and some curved or "
             "straight driving: only motions that mix turning and moving tell the wheel radii, "
             "the axle and the laser's position apart";
  }
}

nlohmann::json parameterObject(const odometry::Vector6& v) {
  nlohmann::json o = nlohmann::json::object();
  for (int k = 0; k < odometry::kParameterCount; ++k) o[odometry::kParameterNames[k]] = v[k];
  return o;
}

nlohmann::json resultJson(const odometry::OdometryResult& r) {
  nlohmann::json j;
  j["status"] = {{"code", r.status.name()}, {"message", r.status.message}};
  j["samples"] = {{"total", r.samples_total},
                  {"used", r.samples_used},
                  {"trimmed", r.samples_trimmed},
                  {"in_covariance", r.samples_in_covariance}};
  if (!r.ok()) return j;
  j["estimate"] = parameterObject(r.estimate.toVector());
  j["standard_error"] = parameterObject(r.standardErrors());
  return j;
}

nlohmann::json subsetJson(const odometry::SubsetScatter& s, const std::string& split) {
  nlohmann::json j;
  j["split"] = split;
  j["count"] = s.subsets.size();
  j["ok"] = s.subsets_ok;
  j["status"] = {{"code", s.status.name()}, {"message", s.status.message}};
  if (s.status.ok()) {
    nlohmann::json p = nlohmann::json::object();
    for (int k = 0; k < odometry::kParameterCount; ++k)
      p[odometry::kParameterNames[k]] = {{"mean", s.mean[k]},
                                         {"spread", s.spread[k]},
                                         {"mean_standard_error", s.mean_standard_error[k]},
                                         {"ratio", s.ratio[k]},
                                         {"ratio_95", {s.ratio_low[k], s.ratio_high[k]}}};
    j["parameters"] = p;
  }
  j["each"] = nlohmann::json::array();
  for (std::size_t i = 0; i < s.subsets.size(); ++i) {
    nlohmann::json e = resultJson(s.subsets[i]);
    e["first_sample"] = s.first_sample[i];
    j["each"].push_back(e);
  }
  return j;
}

nlohmann::json outputJson(const OdometryOptions& o, const odometry::OdometryResult& r,
                          const odometry::SubsetScatter* scatter) {
  nlohmann::json j;
  j["format"] = "lidarcal-odometry/1";
  j["input"] = o.tuples;
  j["method"] = std::string(papers::kOdometry) +
                ": closed form, trimmed at a percentile, inverse Fisher information";
  j["settings"] = {{"trimming_rounds", o.settings.trimming_rounds},
                   {"trim_percentile", o.settings.trim_percentile}};
  j.update(resultJson(r));
  j["fits"] = r.fits;
  j["covariance"] = covarianceJson(odometry::kParameterNames, r.covariance);
  j["residual_sigma"] = {{"x_m", r.residual_sigma[0]},
                         {"y_m", r.residual_sigma[1]},
                         {"theta_rad", r.residual_sigma[2]}};
  if (scatter) j["subsets"] = subsetJson(*scatter, o.split);
  return j;
}

void printResult(const OdometryOptions& o, const odometry::OdometryResult& r) {
  std::printf("%s from %s (%s): %zu used, %zu trimmed in %d rounds at percentile %g\n\n",
              "odometry and laser mounting", plural(r.samples_total, "sample").c_str(),
              papers::kOdometry, r.samples_used, r.samples_trimmed, o.settings.trimming_rounds,
              o.settings.trim_percentile);
  std::printf("| parameter | estimate | standard error | unit |\n|---|---|---|---|\n");
  const odometry::Vector6 value = r.estimate.toVector(), error = r.standardErrors();
  for (int k = 0; k < odometry::kParameterCount; ++k)
    std::printf("| %s | %.3f | %.3f | %s |\n", kShown[k].label, value[k] * kShown[k].scale,
                error[k] * kShown[k].scale, kShown[k].unit);
  std::printf("\nresidual sigma: x %.2f mm, y %.2f mm, theta %.3f deg; covariance from %s\n",
              r.residual_sigma[0] * 1e3, r.residual_sigma[1] * 1e3, rad2deg(r.residual_sigma[2]),
              plural(r.samples_in_covariance, "sample").c_str());
}

void printScatter(const odometry::SubsetScatter& s, const std::string& split) {
  std::printf(
      "\nscatter over %zu %s subsets (%d with an estimate): does the stated standard "
      "error match the spread?\n\n",
      s.subsets.size(), split.c_str(), s.subsets_ok);
  for (std::size_t i = 0; i < s.subsets.size(); ++i)
    if (!s.subsets[i].ok())
      std::printf("subset %zu: %s: %s\n", i + 1, s.subsets[i].status.name(),
                  s.subsets[i].status.message.c_str());
  if (!s.status.ok()) return;
  std::printf(
      "| parameter | mean of subsets | spread | mean stated error | spread / stated | 95 %% "
      "interval | unit |\n|---|---|---|---|---|---|---|\n");
  for (int k = 0; k < odometry::kParameterCount; ++k)
    std::printf("| %s | %.3f | %.3f | %.3f | %.2f | %.2f-%.2f | %s |\n", kShown[k].label,
                s.mean[k] * kShown[k].scale, s.spread[k] * kShown[k].scale,
                s.mean_standard_error[k] * kShown[k].scale, s.ratio[k], s.ratio_low[k],
                s.ratio_high[k], kShown[k].unit);
}

void runOdometry(const OdometryOptions& o) {
  io::checkOutsideInput(o.tuples, o.out);
  io::checkOutputFile(o.out, o.overwrite);
  const std::vector<OdometrySample> samples = io::readOdometryTuples(o.tuples);
  const odometry::OdometryResult result = odometry::calibrateOdometry(samples, o.settings);
  if (!result.ok())
    throw DataError(o.tuples, "calibration",
                    std::string(result.status.name()) + ": " + result.status.message,
                    whatToRecord(result.status.code));
  std::optional<odometry::SubsetScatter> scatter;
  if (o.subsets > 0)
    scatter =
        odometry::scatterOverSubsets(samples, o.subsets, o.settings,
                                     o.split == "interleaved" ? odometry::SubsetSplit::interleaved
                                                              : odometry::SubsetSplit::consecutive);
  io::writeTextAtomically(o.out,
                          outputJson(o, result, scatter ? &*scatter : nullptr).dump(2) + "\n");
  printResult(o, result);
  if (scatter) printScatter(*scatter, o.split);
  if (scatter && !scatter->status.ok())
    std::fprintf(stderr, "lidarcal: warning: no subset scatter: %s\n",
                 scatter->status.message.c_str());
  if (!quiet()) std::fprintf(stderr, "odometry calibration written to %s\n", o.out.c_str());
}

}  // namespace

void addOdometryCommand(CLI::App& app) {
  auto o = std::make_shared<OdometryOptions>();
  CLI::App* sub = app.add_subcommand(
      "odometry", std::string("Calibrate a differential-drive robot's wheel radii and axle and "
                              "its laser's mounting from odometry tuples (") +
                      papers::kOdometry + ")");
  sub->add_option("TUPLES", o->tuples,
                  "Odometry tuples: JSON objects {T, phi_l, phi_r, sm} (docs/FORMAT.md)")
      ->required();
  sub->add_option("-o,--out", o->out, "Result file OUT.json (lidarcal-odometry/1, docs/FORMAT.md)")
      ->required();
  CLI::Option* subsets =
      sub->add_option(
             "--subsets", o->subsets,
             "Also split the tuples into N consecutive subsets, calibrate each and compare "
             "the spread of their estimates with their stated standard errors")
          ->check(CLI::Range(2, 1000));
  sub->add_option("--subset-split", o->split,
                  "consecutive: stretches of the drive; interleaved: every N-th sample (keeps a "
                  "recording made in phases, e.g. turning in place then pivoting, mixed in each)")
      ->check(CLI::IsMember({"consecutive", "interleaved"}))
      ->needs(subsets)
      ->capture_default_str();
  sub->add_option("--rounds", o->settings.trimming_rounds,
                  "Rounds of outlier trimming after the first fit (the published method: 4)")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  sub->add_option("--percentile", o->settings.trim_percentile,
                  "Each round drops the samples above this percentile of disagreement in "
                  "translation or rotation, percent (the published method: 99)")
      ->check(CLI::Range(50.5, 100.0))
      ->capture_default_str();
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT.json if it exists");
  sub->footer(std::string("Method: ") + papers::kOdometry +
              ", \"Simultaneous calibration of odometry and sensor parameters for mobile "
              "robots\", IEEE Transactions on Robotics 29(2). Exit 3 when the motion cannot "
              "determine the parameters.");
  sub->callback([o] { runOdometry(*o); });
}

}  // namespace lidarcal::pipeline
