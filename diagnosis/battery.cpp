// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/battery.hpp"

#include <cmath>
#include <numeric>
#include <utility>

#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis {
namespace {

/// The statistics of a sequence (the residuals of the joint fit): name, variable, description,
/// two-sided, in the battery's output order.
std::vector<StatisticInfo> sequenceStatistics() {
  return {
      {"residual_vs_range", "range",
       "score of a range trend of the residuals beyond the bias polynomial (order n + 1), ~N(0,1)",
       true},
      {"spread_vs_range", "range",
       "score of the noise growing with log f(d) beyond the squared law (clipped squared "
       "residuals), ~N(0,1)",
       true},
      {"residual_vs_incidence", "incidence angle",
       "score of the residuals against 1 - cos(incidence), ~N(0,1)", true},
      {"spread_vs_incidence", "incidence angle",
       "score of the noise growing with -ln cos(incidence), ~N(0,1)", true},
      {"spread_vs_intensity", "intensity",
       "score of the noise growing with ln(I_ref / I), the darkness of the return (0 without "
       "intensities), ~N(0,1)",
       true},
      {"edge_excess", "position within the object",
       "positive minus negative |z| > 3 residuals on the outermost beams, beyond the inner beams' "
       "rate, per sqrt(edge beams)",
       false},
      {"edge_vs_centre_spread", "position within the object",
       "mean clipped z^2 on the outermost beams minus on the inner beams", true},
      {"landmark_identity", "landmark",
       "cube root of chi^2 / dof of the per-landmark mean residuals (overall mean removed)", false},
      {"stop_identity", "stop index",
       "cube root of chi^2 / dof of the per-stop mean residuals (overall mean removed)", false},
      {"heading_within_stop", "stop index",
       "cube root of chi^2 / dof of per-stop rotation scores (a heading shared by all beams of a "
       "stop)",
       false},
      {"common_rotation", "bearing",
       "score of one rotation shared by every beam (zero-angle offset), ~N(0,1)", true},
      {"residual_vs_time", "scan index",
       "score of a linear trend of the residuals over the scans, ~N(0,1)", true},
      {"residual_vs_bearing", "bearing",
       "cube root of chi^2 / 2 of the residuals against cos and sin of the beam angle", false},
      {"path_rotation", "stop index",
       "rotation of the refined stop positions against the commanded path about its centroid, "
       "over the position prior, ~N(0,1)",
       true},
      {"path_scale", "stop index",
       "stretch of the refined stop positions against the commanded path about its centroid, over "
       "the position prior, ~N(0,1)",
       true},
      {"bearing_within_stop_correlation", "stop index",
       "ln F of the sighting bearing residuals between stops against within stops", false},
      {"tail_weight", "residual", "excess kurtosis of the standardised residuals", false},
      {"quantisation_1mm", "reading",
       "resultant length of the readings' phase on a 1 mm grid (1: on the grid)", false},
  };
}

/// The statistics of a static scene (repeated scans of walls), as sequenceStatistics().
std::vector<StatisticInfo> staticStatistics() {
  return {
      {"spread_vs_range", "range",
       "score of the noise growing with ln(mean reading) beyond the squared law, ~N(0,1)", true},
      {"spread_vs_incidence", "incidence angle",
       "score of the noise growing with -ln cos(incidence), ~N(0,1)", true},
      {"spread_vs_intensity", "intensity",
       "score of the noise growing with ln(I_median / I), the darkness of the return, away from "
       "discontinuities (0 without intensities that vary), ~N(0,1)",
       true},
      {"spread_vs_bearing", "bearing",
       "cube root of chi^2 / 2 of the noise against cos and sin of the beam angle", false},
      {"residual_vs_time", "scan index",
       "score of a trend shared by all beams over the scans, ~N(0,1)", true},
      {"lag1_correlation", "scan index",
       "pooled lag-1 correlation of successive readings of a beam, times sqrt(pairs)", true},
      {"edge_excess", "position within the object",
       "|z| > 3 readings at depth discontinuities beyond the rate elsewhere, per sqrt(edge "
       "readings)",
       false},
      {"edge_vs_centre_spread", "position within the object",
       "mean clipped z^2 at depth discontinuities minus elsewhere", true},
      {"tail_weight", "residual",
       "excess kurtosis of the standardised residuals (away from discontinuities)", false},
      {"quantisation", "reading",
       "resultant length of the readings' phase on the detected grid (1: on the grid)", false},
      {"wall_curvature", "incidence angle",
       "incidence bias b (1 - cos phi) fitted on the wall lines, over its standard error", true},
      {"wall_roughness_mm", "wall", "scatter of the beam means about the wall model, mm", false},
      {"range_offset_mm", "wall", "range offset alpha_0 the walls' straightness implies, mm", true},
  };
}

}  // namespace

const std::vector<StatisticInfo>& statisticInfo(DiagnoseMode mode) {
  static const std::vector<StatisticInfo> sequence = sequenceStatistics();
  static const std::vector<StatisticInfo> static_scene = staticStatistics();
  return mode == DiagnoseMode::sequence ? sequence : static_scene;
}

const char* statisticOf(Effect e, DiagnoseMode mode) {
  const char* s =
      mode == DiagnoseMode::sequence ? info(e).sequence_statistic : info(e).static_statistic;
  return s ? s : "";
}

Discrepancy makeDiscrepancy(std::string name, std::string variable, std::string description,
                            double value, const std::vector<double>& replicas, bool two_sided) {
  Discrepancy d;
  d.name = std::move(name);
  d.variable = std::move(variable);
  d.description = std::move(description);
  d.value = value;
  d.two_sided = two_sided;
  std::vector<double> r;
  for (double v : replicas)
    if (std::isfinite(v)) r.push_back(v);
  if (!r.empty()) {
    d.replica_mean = std::accumulate(r.begin(), r.end(), 0.0) / static_cast<double>(r.size());
    double var = 0.0;
    for (double v : r) var += (v - d.replica_mean) * (v - d.replica_mean);
    d.replica_sd = r.size() > 1 ? std::sqrt(var / static_cast<double>(r.size() - 1)) : 0.0;
  }
  d.p_value = replicaPValue(value, replicas, two_sided, &d.effect_size);
  return d;
}

std::vector<Discrepancy> makeBattery(const std::vector<StatisticInfo>& infos,
                                     const std::map<std::string, double>& measured,
                                     const std::map<std::string, std::vector<double>>& replicas) {
  std::vector<Discrepancy> out;
  for (const auto& s : infos) {
    const auto it = measured.find(s.name);
    if (it == measured.end()) continue;
    const auto rep = replicas.find(s.name);
    out.push_back(makeDiscrepancy(s.name, s.variable, s.description, it->second,
                                  rep != replicas.end() ? rep->second : std::vector<double>{},
                                  s.two_sided));
  }
  return out;
}

void setScore(CandidateResult& r, const std::vector<Discrepancy>& battery) {
  for (const auto& d : battery)
    if (d.name == r.statistic) {
      r.score_p_value = d.p_value;
      r.effect_size = d.effect_size;
    }
}

}  // namespace lidarcal::diagnosis
