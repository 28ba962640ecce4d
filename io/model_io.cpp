// SPDX-License-Identifier: BSD-3-Clause
#include "io/model_io.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/json_number.hpp"
#include "io/json_util.hpp"

namespace lidarcal::io {
namespace {

using ojson = nlohmann::ordered_json;

ojson noiseJson(const NoiseModel& n) {
  ojson j{{"kind", toString(n.kind)}};
  if (n.kind == NoiseKind::polynomial) j["beta"] = n.beta;
  if (n.kind == NoiseKind::constant || n.kind == NoiseKind::squared || n.kind == NoiseKind::power)
    j["sigma_e"] = n.sigma_e;
  if (n.kind == NoiseKind::power) j["exponent"] = n.exponent;
  return j;
}

/// The bias with the standard error of each coefficient (from alpha_covariance, when computed).
ojson biasJson(const CalibrationModel& m) {
  ojson j{{"order", m.model.bias.order()}, {"alpha", m.model.bias.alpha}};
  const std::size_t n = m.model.bias.alpha.size();
  if (m.alpha_covariance.size() == n * n) {
    ojson se = ojson::array();
    for (std::size_t i = 0; i < n; ++i)
      se.push_back(jsonNumber(std::sqrt(m.alpha_covariance[i * n + i])));
    j["standard_error"] = se;
  }
  return j;
}

/// The model discrepancy beside the curve's covariance (docs/FORMAT.md, "discrepancy").
ojson discrepancyJson(const Discrepancy& d) {
  ojson j{{"method", d.method}, {"sigma_m", jsonNumber(d.sigma_m)}};
  if (d.estimated()) {
    j["dof"] = d.dof;
    j["entries"] = d.entries;
    j["tape_sigma_m"] = jsonNumber(d.tape_sigma_m);
  }
  j["note"] = d.note;
  return j;
}

Discrepancy readDiscrepancy(const JsonView& v) {
  v.requireObject();
  Discrepancy d;
  d.method = v.getString("method", "none");
  if (d.method != "none" && d.method != "reml") v.fail("method", "must be \"none\" or \"reml\"");
  d.note = v.getString("note", "");
  if (d.method == "none") return d;
  d.sigma_m = v.getNonNegative("sigma_m");
  d.dof = v.getPositiveInt("dof");
  d.entries = static_cast<std::size_t>(v.getPositiveInt("entries", d.dof + 1));
  if (v.has("tape_sigma_m") && !v.json().at("tape_sigma_m").is_null())
    d.tape_sigma_m = v.getNonNegative("tape_sigma_m");
  return d;
}

}  // namespace

void writeModel(const std::filesystem::path& file, const CalibrationModel& m) {
  writeTextAtomically(file, modelJson(m).dump(2) + "\n");
}

namespace {

ojson ordersJson(const CalibrationModel& m) {
  ojson orders = ojson::array();
  for (const auto& o : m.orders)
    orders.push_back(ojson{{"order", o.order},
                           {"alpha", o.alpha},
                           {"aic", jsonNumber(o.aic)},
                           {"bic", jsonNumber(o.bic)},
                           {"validation_mse_m2", jsonNumber(o.validation_mse_m2)},
                           {"test_mse_m2", jsonNumber(o.test_mse_m2)},
                           {"invertible", o.invertible}});
  return ojson{{"rule", m.order_rule},
               {"order_aic", m.order_aic},
               {"order_validation", m.order_validation},
               {"table", orders}};
}

ojson landmarksJson(const CalibrationModel& m) {
  ojson landmarks = ojson::array();
  for (const auto& l : m.landmarks)
    landmarks.push_back(
        ojson{{"id", l.id},
              {"x_m", l.x_m},
              {"y_m", l.y_m},
              {"radius_m", l.radius_m},
              {"covariance_m2",
               ojson::array({jsonNumber(l.covariance_m2[0]), jsonNumber(l.covariance_m2[1]),
                             jsonNumber(l.covariance_m2[2]), jsonNumber(l.covariance_m2[3])})},
              {"stops", l.stops},
              {"status", l.status}});
  return landmarks;
}

ojson stopsJson(const CalibrationModel& m) {
  ojson stops = ojson::array();
  for (const auto& p : m.stop_poses)
    stops.push_back(ojson{{"x_m", p.x_m}, {"y_m", p.y_m}, {"yaw_rad", p.yaw_rad}});
  return stops;
}

ojson noiseEstimatorsJson(const NoiseFits& nf) {
  return ojson{
      {"alhashimi2021_beta", nf.alhashimi2021_beta},
      {"alhashimi2016_closed_form",
       ojson{{"alpha", nf.alhashimi2016_cf_alpha}, {"sigma_e", nf.alhashimi2016_cf_sigma_e}}},
      {"alhashimi2016_ml",
       ojson{{"alpha", nf.alhashimi2016_ml_alpha}, {"sigma_e", nf.alhashimi2016_ml_sigma_e}}},
      {"exponent_test",
       ojson{{"log_likelihood_h0_h3",
              ojson::array({jsonNumber(nf.exponent_loglik[0]), jsonNumber(nf.exponent_loglik[1]),
                            jsonNumber(nf.exponent_loglik[2]), jsonNumber(nf.exponent_loglik[3])})},
             {"best", nf.exponent_best},
             {"batches", nf.exponent_batches}}}};
}

ojson diagnosticsJson(const CalibrationModel& m) {
  return ojson{{"status", m.status.name()},
               {"message", m.status.message},
               {"iterations", m.iterations},
               {"residual_rms_m", m.residual_rms_m},
               {"readings", m.readings},
               {"pose_scatter_m", m.pose_scatter_m},
               {"heading_scatter_rad", m.heading_scatter_rad},
               {"offset_radius_correlation", jsonNumber(m.offset_radius_correlation)}};
}

/// The parts written only when present, so that models without them keep their bytes.
void addOptionalParts(const CalibrationModel& m, ojson& j) {
  if (m.fitted_range_m) {
    const auto [lo, hi] = *m.fitted_range_m;
    j["fitted_range"] = ojson{{"d_min_m", lo},
                              {"d_max_m", hi},
                              {"reading_min_m", m.model.bias(lo)},
                              {"reading_max_m", m.model.bias(hi)}};
  }
  if (m.motion_prior) j["diagnostics"]["motion_prior"] = true;
  if (!m.warnings.empty()) j["warnings"] = m.warnings;
  if (!m.noise_fits.unavailable.empty()) {
    ojson na = ojson::object();
    for (const auto& [k, v] : m.noise_fits.unavailable) na[k] = v;
    j["noise_estimators"]["unavailable"] = na;
  }
  if (!m.effects.empty()) {
    ojson fx = ojson::object();
    for (const auto& [k, v] : m.effects) fx[k] = jsonNumber(v);
    j["effects"] = fx;
  }
}

}  // namespace

ojson modelJson(const CalibrationModel& m) {
  ojson j{{"format", m.format},
          {"method", m.method},
          {"sensor", ojson{{"name", m.sensor_name},
                           {"beams", m.beams ? ojson(*m.beams) : ojson(nullptr)},
                           {"range_min_m", m.model.range_min_m},
                           {"range_max_m", m.model.range_max_m}}},
          {"bias", biasJson(m)},
          {"noise", noiseJson(m.model.noise)},
          {"sigma_theta_rad", m.sigma_theta_rad},
          {"alpha_covariance", m.alpha_covariance},
          {"discrepancy", discrepancyJson(m.discrepancy)},
          {"order_selection", ordersJson(m)},
          {"noise_estimators", noiseEstimatorsJson(m.noise_fits)},
          {"landmarks", landmarksJson(m)},
          {"stops", stopsJson(m)},
          {"diagnostics", diagnosticsJson(m)}};
  addOptionalParts(m, j);
  return j;
}

CalibrationModel readModel(const std::filesystem::path& file) {
  return modelFromJson(readJsonFile(file), file.string());
}

namespace {

void requireModelFormat(const JsonView& root, const std::string& format) {
  if (format == "lidarcal-rig-model/1")
    root.fail("format",
              "holds one model per sensor of a rig (\"lidarcal-rig-model/1\"): pick one with "
              "--sensor NAME "
              "(`correct`, `export`) or the node's sensor parameter");
  if (format != "lidarcal-model/1")
    root.fail("format",
              "not a lidarcal model file (expected \"lidarcal-model/1\"); create one with "
              "`lidarcal calibrate`");
}

/// The sensor, bias and noise: what correcting a reading needs.
void readRangeModel(const JsonView& root, CalibrationModel& m) {
  const JsonView sensor = root.child("sensor");
  m.sensor_name = sensor.getString("name", "");
  if (sensor.has("beams") && !sensor.json().at("beams").is_null())
    m.beams = sensor.getPositiveInt("beams");
  m.model.range_min_m = sensor.getNonNegative("range_min_m");
  m.model.range_max_m = sensor.getPositive("range_max_m");
  if (m.model.range_min_m >= m.model.range_max_m)
    sensor.fail("range_min_m", "must be smaller than range_max_m");
  const JsonView bias = root.child("bias");
  m.model.bias.alpha = bias.getNumbers("alpha");
  if (m.model.bias.alpha.size() < 2 || m.model.bias.alpha.size() > 10)
    bias.fail("alpha", "must hold 2 to 10 coefficients (order 1 to 9)");
  const JsonView noise = root.child("noise");
  const std::string kind = noise.getString("kind");
  if (!parseNoiseKind(kind, m.model.noise.kind))
    noise.fail("kind", "unknown noise kind '" + kind + "'");
  if (m.model.noise.kind == NoiseKind::polynomial)
    m.model.noise.beta = noise.getNumbers("beta");
  else if (m.model.noise.kind != NoiseKind::none)
    m.model.noise.sigma_e = noise.getNonNegative("sigma_e");
  if (m.model.noise.kind == NoiseKind::power) m.model.noise.exponent = noise.getNumber("exponent");
  m.sigma_theta_rad = root.getNonNegative("sigma_theta_rad", 0.0);
}

void readLandmarksAndStops(const JsonView& root, CalibrationModel& m) {
  if (root.has("landmarks"))
    for (const auto& e : root.array("landmarks")) {
      e.requireObject();
      CalibratedLandmark l;
      l.id = e.getInt("id");
      l.x_m = e.getNumber("x_m");
      l.y_m = e.getNumber("y_m");
      l.radius_m = e.getNonNegative("radius_m", 0.0);
      l.stops = e.getInt("stops", 0);
      l.status = e.getString("status", "ok");
      m.landmarks.push_back(l);
    }
  if (root.has("stops"))
    for (const auto& e : root.array("stops")) {
      e.requireObject();
      m.stop_poses.push_back(Pose2{e.getNumber("x_m"), e.getNumber("y_m"), e.getNumber("yaw_rad")});
    }
}

/// The fitted range, warnings, uncertainty, effects and the fit's status.
void readFitFacts(const JsonView& root, CalibrationModel& m) {
  if (root.has("fitted_range")) {
    const JsonView fr = root.child("fitted_range");
    const double lo = fr.getNonNegative("d_min_m"), hi = fr.getPositive("d_max_m");
    if (!(lo < hi)) fr.fail("d_min_m", "must be smaller than d_max_m");
    m.fitted_range_m = std::make_pair(lo, hi);
  }
  if (root.has("warnings"))
    for (const auto& w : root.array("warnings"))
      m.warnings.push_back(w.json().is_string() ? w.json().get<std::string>() : w.json().dump());
  if (root.has("alpha_covariance")) {
    const std::vector<double> c = root.getNumbers("alpha_covariance");
    if (c.size() == m.model.bias.alpha.size() * m.model.bias.alpha.size()) m.alpha_covariance = c;
  }
  if (root.has("discrepancy")) m.discrepancy = readDiscrepancy(root.child("discrepancy"));
  if (root.has("effects")) {
    const JsonView fx = root.child("effects");
    fx.requireObject();
    for (const auto& [k, v] : fx.json().items())
      if (!v.is_null()) m.effects[k] = fx.getNumber(k);
  }
  if (root.has("diagnostics")) {
    const JsonView d = root.child("diagnostics");
    const std::string status = d.getString("status", "ok");
    const std::optional<StatusCode> code = parseStatusCode(status);
    if (!code)
      d.fail("status",
             "'" + status +
                 "' is not a status lidarcal writes (ok, joint_failed, ...: docs/ERRORS.md)");
    m.status = Status{*code, d.getString("message", "")};
  }
}

}  // namespace

CalibrationModel modelFromJson(const nlohmann::json& j, const std::string& file,
                               const std::string& path) {
  const JsonView root(file, j, path);
  root.requireObject();
  CalibrationModel m;
  m.format = root.getString("format", "");
  requireModelFormat(root, m.format);
  m.method = root.getString("method", "");
  readRangeModel(root, m);
  readLandmarksAndStops(root, m);
  readFitFacts(root, m);
  return m;
}

}  // namespace lidarcal::io
