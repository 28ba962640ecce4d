// SPDX-License-Identifier: BSD-3-Clause
// diagnosis.json (docs/FORMAT.md): every number of a diagnosis, null where it is not finite.
#include <cmath>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "io/json_number.hpp"
#include "pipeline/reports/diagnose_report.hpp"

namespace lidarcal::pipeline {
namespace {

using ojson = nlohmann::ordered_json;
using diagnosis::DiagnosisResult;
using diagnosis::ResidualRecord;

ojson numbers(const std::map<std::string, double>& m) {
  ojson j = ojson::object();
  for (const auto& [k, v] : m) j[k] = io::jsonNumber(v);
  return j;
}

ojson closenessJson(const diagnosis::Closeness& c) {
  return ojson{{"ks_distance", io::jsonNumber(c.ks_distance)},
               {"variance_ratio_median_abs_log", io::jsonNumber(c.variance_ratio_median_abs_log)},
               {"groups", c.groups}};
}

ojson baselineJson(const DiagnosisResult& r, const DiagnosisSource& src) {
  ojson baseline{
      {"bias_alpha", r.baseline.bias.alpha},
      {"noise", ojson{{"kind", toString(r.baseline.noise.kind)},
                      {"sigma_e", io::jsonNumber(r.baseline.noise.sigma_e)}}},
      {"range_min_m", r.baseline.range_min_m},
      {"range_max_m",
       io::jsonNumber(r.baseline.range_max_m < 1e8 ? r.baseline.range_max_m : std::nan(""))},
      {"neg_log_likelihood", io::jsonNumber(r.baseline_neg_log_likelihood)},
      {"heldout_nats_per_point", io::jsonNumber(r.baseline_heldout_nats_per_point)},
      {"fitted", numbers(r.baseline_extra)}};
  if (r.mode == diagnosis::DiagnoseMode::sequence) {
    baseline["sigma_theta_rad"] = io::jsonNumber(r.baseline_sigma_theta_rad);
    baseline["landmark_radius_m"] = io::jsonNumber(r.baseline_radius_m);
    baseline["landmark_radius_known"] = r.radius_known;
  } else {
    ojson walls = ojson::array();
    for (const auto& w : src.walls)
      walls.push_back(ojson{{"normal_rad", w.normal_rad},
                            {"distance_m", w.distance_m},
                            {"first_angle_rad", w.first_angle_rad},
                            {"last_angle_rad", w.last_angle_rad},
                            {"bins", w.bins},
                            {"rms_m", io::jsonNumber(w.rms_m)}});
    baseline["walls"] = walls;
  }
  return baseline;
}

ojson batteryJson(const std::vector<diagnosis::Discrepancy>& battery) {
  ojson out = ojson::array();
  for (const auto& d : battery)
    out.push_back(ojson{{"name", d.name},
                        {"variable", d.variable},
                        {"value", io::jsonNumber(d.value)},
                        {"replica_mean", io::jsonNumber(d.replica_mean)},
                        {"replica_sd", io::jsonNumber(d.replica_sd)},
                        {"effect_size", io::jsonNumber(d.effect_size)},
                        {"p_value", io::jsonNumber(d.p_value)},
                        {"two_sided", d.two_sided},
                        {"description", d.description}});
  return out;
}

ojson candidateJson(const diagnosis::CandidateResult& c) {
  ojson j{{"effect", toString(c.effect)},
          {"p_value", io::jsonNumber(c.p_value)},
          {"p_holm", io::jsonNumber(c.p_holm)},
          {"p_heldout", io::jsonNumber(c.p_heldout)},
          {"p_likelihood_ratio", io::jsonNumber(c.p_likelihood_ratio)},
          {"heldout_gain_nats_per_point", io::jsonNumber(c.heldout_gain_nats_per_point)},
          {"heldout_gain_se", io::jsonNumber(c.heldout_gain_se)},
          {"delta_aic", io::jsonNumber(c.delta_aic)},
          {"parameters", c.parameters},
          {"significant", c.significant},
          {"identifiable", c.identifiable},
          {"applicable", c.applicable},
          {"information_ratio", io::jsonNumber(c.information_ratio)},
          {"standard_error", io::jsonNumber(c.standard_error)},
          {"statistic", c.statistic},
          {"statistic_p_value", io::jsonNumber(c.score_p_value)},
          {"statistic_effect_size", io::jsonNumber(c.effect_size)},
          {"estimates", numbers(c.estimates)}};
  if (c.calibration_mse_ratio > 0.0)
    j["calibration_mse_ratio"] = io::jsonNumber(c.calibration_mse_ratio);
  if (!c.note.empty()) j["note"] = c.note;
  return j;
}

/// Static mode: what the tails are made of (diagnosis/tails.hpp); null when not fitted.
ojson tailsJson(const diagnosis::TailAttribution& t) {
  if (!t.fitted)
    return t.note.empty() ? ojson(nullptr) : ojson{{"fitted", false}, {"note", t.note}};
  ojson covs = ojson::array();
  for (const auto& c : t.covariates)
    covs.push_back(
        ojson{{"covariate", c.covariate},
              {"effect", toString(c.effect)},
              {"coefficient", io::jsonNumber(c.coefficient)},
              {"unique_gain_nats_per_point", io::jsonNumber(c.unique_gain_nats_per_point)},
              {"unique_gain_se", io::jsonNumber(c.unique_gain_se)},
              {"p_value", io::jsonNumber(c.p_value)},
              {"p_holm", io::jsonNumber(c.p_holm)},
              {"share", io::jsonNumber(c.share)},
              {"significant", c.significant}});
  ojson beams = ojson::array();
  for (const auto& b : t.top_beams)
    beams.push_back(ojson{{"bearing_rad", io::jsonNumber(b.bearing_rad)},
                          {"range_m", io::jsonNumber(b.range_m)},
                          {"incidence_rad", io::jsonNumber(b.incidence_rad)},
                          {"intensity", io::jsonNumber(b.intensity)},
                          {"edge", b.edge},
                          {"readings", b.readings},
                          {"tail_fraction", io::jsonNumber(b.tail_fraction)},
                          {"tail_probability", io::jsonNumber(b.tail_probability)},
                          {"class", b.cls}});
  return ojson{{"fitted", true},
               {"cause", t.cause},
               {"significant", t.significant},
               {"p_value", io::jsonNumber(t.p_value)},
               {"pooled",
                ojson{{"fraction", io::jsonNumber(t.pooled_fraction)},
                      {"wide_scale", io::jsonNumber(t.pooled_wide_scale)},
                      {"heldout_gain_nats_per_point", io::jsonNumber(t.pooled_gain_nats_per_point)},
                      {"heldout_gain_se", io::jsonNumber(t.pooled_gain_se)}}},
               {"explained", ojson{{"heldout_gain_nats_per_point",
                                    io::jsonNumber(t.explained_gain_nats_per_point)},
                                   {"heldout_gain_se", io::jsonNumber(t.explained_gain_se)}}},
               {"covariates", covs},
               {"model", numbers(t.model)},
               {"tail_readings", io::jsonNumber(t.tail_readings)},
               {"tail_readings_by_class", numbers(t.tail_readings_by_class)},
               {"readings_by_class", numbers(t.readings_by_class)},
               {"top_beams", beams},
               {"robust", numbers(t.robust)}};
}

/// The named effect's gain: held out, delta AIC, closeness of simulations, calibration.
ojson gainJson(const DiagnosisResult& r, bool named) {
  ojson gain{{"heldout_nats_per_point",
              named ? io::jsonNumber(r.gain_heldout_nats_per_point) : ojson(nullptr)},
             {"delta_aic", named ? io::jsonNumber(r.gain_delta_aic) : ojson(nullptr)},
             {"closeness", ojson{{"baseline_simulation", closenessJson(r.closeness_baseline)},
                                 {"extended_simulation",
                                  named ? closenessJson(r.closeness_extended) : ojson(nullptr)}}}};
  if (r.calibration_mse_ratio_baseline > 0.0)
    gain["calibration_mse_ratio"] = ojson{
        {"baseline", io::jsonNumber(r.calibration_mse_ratio_baseline)},
        {"extended", named ? io::jsonNumber(r.calibration_mse_ratio_extended) : ojson(nullptr)}};
  return gain;
}

ojson dataJson(const DiagnosisResult& r, const DiagnosisSource& src) {
  ojson data{{"path", src.data.string()},
             {"scans", r.scans},
             {"stops", r.stops},
             {"readings", r.readings}};
  data[r.mode == diagnosis::DiagnoseMode::sequence ? "landmarks" : "walls"] = r.landmarks;
  if (!src.sensor.empty()) data["sensor"] = src.sensor;
  if (!src.selection.empty()) data["selection"] = src.selection;
  if (r.mode == diagnosis::DiagnoseMode::sequence)
    data["readings_beside_poles"] = src.beside_pole_readings;
  if (!src.model.empty()) data["corrected_with_model"] = src.model;
  return data;
}

}  // namespace

nlohmann::ordered_json diagnosisJson(const DiagnosisResult& r, const DiagnosisSource& src) {
  ojson candidates = ojson::array();
  for (const auto& c : r.candidates) candidates.push_back(candidateJson(c));
  const bool named = !r.extended_parameters.empty() || !r.scene_keys.empty();
  ojson extended = named ? ojson{{"effect", r.primary_cause},
                                 {"parameters", numbers(r.extended_parameters)},
                                 {"bias_alpha", r.extended_bias_alpha},
                                 {"scene_keys", numbers(r.scene_keys)}}
                         : ojson(nullptr);
  return ojson{{"format", "lidarcal-diagnosis/1"},
               {"mode", toString(r.mode)},
               {"status", r.status.name()},
               {"message", r.status.message},
               {"data", dataJson(r, src)},
               {"settings", ojson{{"seed", r.seed},
                                  {"replicas", r.replicas},
                                  {"folds", r.folds},
                                  {"multiple_testing", "holm"}}},
               {"baseline", baselineJson(r, src)},
               {"battery", batteryJson(r.battery)},
               {"candidates", candidates},
               {"primary_cause", r.primary_cause},
               {"decision", r.decision},
               {"tails", tailsJson(r.tails)},
               {"extended_model", extended},
               {"gain", gainJson(r, named)}};
}

}  // namespace lidarcal::pipeline
