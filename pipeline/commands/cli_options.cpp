// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/commands/cli_options.hpp"

#include <CLI/CLI.hpp>

#include "common/errors.hpp"
#include "pipeline/reports/papers.hpp"

namespace lidarcal::pipeline {

void addThreadsOption(CLI::App* app, int& threads, const std::string& work) {
  app->add_option("--threads", threads,
                  "Threads (0: the machine's cores, at most 8) " + work +
                      "; the output does not depend on it")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

void addCalibrationOptions(CLI::App* app, const std::shared_ptr<CalibrationOptions>& o) {
  addThreadsOption(
      app, o->threads,
      "detecting scans, fitting the bias orders and (run) correcting scans side by side");
  app->add_option("--method", o->method,
                  std::string("closed-form: triangulation + least squares as in ") +
                      papers::kLandmarks +
                      "; joint: refine poses, landmarks "
                      "and bias together from every reading")
      ->check(CLI::IsMember({"closed-form", "joint"}))
      ->capture_default_str();
  app->add_option("--max-order", o->max_order, "Largest bias polynomial order tried (n_max)")
      ->check(CLI::Range(1, 6))
      ->capture_default_str();
  app->add_option("--order-rule", o->order_rule,
                  "Order rule of the closed form: aic or validation (fit/choose/test split)")
      ->check(CLI::IsMember({"aic", "validation"}))
      ->capture_default_str();
  app->add_option("--joint-order-rule", o->joint_order_rule,
                  "Order rule of the joint refinement: aic, aic-parsimonious (smallest order "
                  "within 2 of the best AIC) or bic")
      ->check(CLI::IsMember({"aic", "aic-parsimonious", "bic"}))
      ->capture_default_str();
  app->add_option("--noise", o->noise,
                  std::string("Noise law: squared (") + papers::kTriangulation +
                      ": sigma_e f(d)^2), polynomial (" + papers::kLandmarks + "), constant")
      ->check(CLI::IsMember({"squared", "polynomial", "constant"}))
      ->capture_default_str();
  app->add_option("--sigma-s", o->sigma_s_m,
                  "How far a stop may be from its commanded position (std. dev., m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app->add_option("--sigma-psi", o->sigma_psi_deg,
                  "How far a stop's heading may be from the command (std. dev., degrees)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app->add_option("--sigma-theta", o->sigma_theta_deg,
                  "Bearing noise assumed by the triangulation weights (degrees)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app->add_option("--radius", o->radius_m,
                  "Landmark radius in metres (default: sequence.json, else estimated)")
      ->check(CLI::PositiveNumber);
  app->add_option("--min-stops", o->min_stops,
                  "A landmark must be seen from at least this many stops")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  addInlierThresholdOption(app, o->inlier_threshold);
  app->add_option("--motion-prior", o->motion_prior,
                  "Odometry between consecutive stops as a prior of the joint refinement: auto (on "
                  "when the robot never "
                  "stopped: at least 20 stops, most of one scan each), on, or off (every stop tied "
                  "to its own commanded pose)")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  app->add_option(
      "--effects", o->effects,
      "Comma-separated effect terms for the joint refinement, as `lidarcal diagnose` names them: " +
          effectNames([](const EffectInfo& i) {
            return i.joint_term && i.effect != Effect::heading_error;
          }) +
          " (heavy_tails: Student-t noise; quantisation: the readings rounded to the grid they lie "
          "on; "
          "dark_surface: noise growing as the return intensity falls, needs scans with "
          "intensities; per-stop "
          "headings, heading_error, are always refined)");
}

calibration::CalibrationConfig calibrationConfig(const CalibrationOptions& o) {
  calibration::CalibrationConfig c;
  c.method =
      o.method == "closed-form" ? calibration::Method::closed_form : calibration::Method::joint;
  c.threads = o.threads;
  c.max_order = o.max_order;
  c.closed_form_rule = o.order_rule == "validation" ? calibration::OrderRule::validation
                                                    : calibration::OrderRule::aic;
  c.joint_rule = o.joint_order_rule == "aic"   ? calibration::JointOrderRule::aic
                 : o.joint_order_rule == "bic" ? calibration::JointOrderRule::bic
                                               : calibration::JointOrderRule::aic_parsimonious;
  if (!parseNoiseKind(o.noise, c.noise))
    throw InputError("", "--noise", "unknown noise law '" + o.noise + "'");
  c.triangulation.sigma_s_m = o.sigma_s_m;
  c.triangulation.sigma_theta_rad = deg2rad(o.sigma_theta_deg);
  c.triangulation.min_stops = o.min_stops;
  c.joint.sigma_s_m = o.sigma_s_m;
  c.joint.sigma_psi_rad = deg2rad(o.sigma_psi_deg);
  c.joint.motion = o.motion_prior == "on"    ? calibration::MotionPrior::on
                   : o.motion_prior == "off" ? calibration::MotionPrior::off
                                             : calibration::MotionPrior::automatic;
  std::string rest = o.effects;
  while (!rest.empty()) {
    const auto comma = rest.find(',');
    const std::string e = rest.substr(0, comma);
    rest = comma == std::string::npos ? "" : rest.substr(comma + 1);
    if (e.empty()) continue;
    const std::optional<Effect> effect = parseEffect(e);
    if (!effect || !c.joint.effects.enable(*effect))
      throw InputError("", "--effects", "unknown effect '" + e + "'",
                       "use " + effectNames([](const EffectInfo& i) { return i.joint_term; }));
  }
  if ((c.joint.effects.incidence_noise || c.joint.effects.noise_exponent ||
       c.joint.effects.dark_noise) &&
      c.noise == NoiseKind::polynomial)
    throw InputError(
        "", "--effects",
        "incidence_noise, range_noise_law and dark_surface need --noise squared or constant");
  return c;
}

void addInlierThresholdOption(CLI::App* app, std::vector<double>& threshold) {
  app->add_option("--inlier-threshold", threshold,
                  "Inlier threshold of the circle and line fits, t(r) = A + B r^2 metres (r: "
                  "range), as A,B; about three standard deviations of the sensor's range noise. "
                  "Default 0.01,0.005 (a triangulation lidar, noise growing with range squared; "
                  "poles count as too far once t exceeds twice their radius); a time-of-flight "
                  "sensor with millimetre noise: e.g. 0.01,0.0005")
      ->expected(2)
      ->delimiter(',')
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

void applyInlierThreshold(const std::vector<double>& threshold,
                          detectors::DetectionConfig& detection) {
  if (!(threshold.at(0) > 0.0))
    throw InputError("", "--inlier-threshold", "A (the threshold at range 0) must be > 0");
  detection.threshold_m = threshold.at(0);
  detection.threshold_per_m2 = threshold.at(1);
}

detectors::SequenceDetectionConfig detectionConfig(const CalibrationOptions& o) {
  detectors::SequenceDetectionConfig c;
  if (o.radius_m > 0.0) c.detection.landmark_radius_m = o.radius_m;
  c.association.min_stops = o.min_stops;
  c.threads = o.threads;
  applyInlierThreshold(o.inlier_threshold, c.detection);
  return c;
}

calibration::InversionMethod CorrectionOptions::method() const {
  return inversion == "ml" ? calibration::InversionMethod::ml : calibration::InversionMethod::ls;
}

calibration::Outside CorrectionOptions::outsidePolicy() const {
  calibration::Outside o = calibration::kDefaultOutside;
  if (!calibration::parseOutside(outside, o))
    throw InputError("", "--outside", "unknown policy '" + outside + "'",
                     "use " + calibration::outsideNames());
  return o;
}

void addCorrectionOptions(CLI::App* app, const std::shared_ptr<CorrectionOptions>& o) {
  app->add_option("--inversion", o->inversion,
                  "ls: the distance whose f equals the reading (" +
                      std::string(papers::kTriangulation) +
                      ", eq. 30); ml: the most likely distance (eq. 28, squared noise law only)")
      ->check(CLI::IsMember({"ls", "ml"}))
      ->capture_default_str();
  app->add_option("--outside", o->outside,
                  "Readings beyond the distances the model was fitted over (model.json "
                  "fitted_range): linear continues "
                  "the fitted correction past the edge at its slope there (no step, no kink; the "
                  "default), keep leaves "
                  "them as read, extrapolate applies the polynomial itself, drop removes them (no "
                  "return). Corrected "
                  "scans mark each point in their `correction` field (docs/FORMAT.md)")
      ->check(CLI::IsMember(calibration::outsidePolicies()))
      ->capture_default_str();
}

}  // namespace lidarcal::pipeline
