// SPDX-License-Identifier: BSD-3-Clause
#include "studies/figures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <stdexcept>

#include "common/stats_util.hpp"
#include "studies/figure_text.hpp"

namespace lidarcal::studies {

const char* toString(Figure f) {
  switch (f) {
    case Figure::fig7:
      return "fig7";
    case Figure::fig8:
      return "fig8";
    case Figure::fig9:
      return "fig9";
    case Figure::fig10:
      return "fig10";
    case Figure::fig11:
      return "fig11";
  }
  return "unknown";
}

bool parseFigure(const std::string& name, Figure& f) {
  for (Figure x : allFigures())
    if (name == toString(x)) {
      f = x;
      return true;
    }
  return false;
}

std::vector<Figure> allFigures() {
  return {Figure::fig7, Figure::fig8, Figure::fig9, Figure::fig10, Figure::fig11};
}

StudyGrids StudyGrids::quick() {
  StudyGrids g;
  g.sigma_s_m = {0.001, 0.01, 0.1};
  g.sigma_theta_deg = {0.5, 2.0, 5.0};
  g.landmarks = {1, 3, 5};
  g.sigma_s_vs_landmarks_m = {0.001, 0.01, 0.1};
  return g;
}

std::vector<Cell> figureCells(Figure f, const StudyGrids& g) {
  std::vector<Cell> cells;
  auto add = [&](int L, double ss, double deg) { cells.push_back(Cell{L, ss, deg2rad(deg)}); };
  switch (f) {
    case Figure::fig7:
      for (double t : g.sigma_theta_deg)
        for (double ss : g.sigma_s_m) add(g.fig7_landmarks, ss, t);
      break;
    case Figure::fig8:
    case Figure::fig11:
      for (double ss : g.sigma_s_vs_landmarks_m)
        for (int L : g.landmarks) add(L, ss, g.sigma_theta_vs_landmarks_deg);
      break;
    case Figure::fig9:
      for (int L : g.fig9_landmarks)
        for (double t : g.sigma_theta_deg)
          for (double ss : g.sigma_s_m) add(L, ss, t);
      break;
    case Figure::fig10:
      for (double t : g.sigma_theta_deg)
        for (double ss : g.sigma_s_m) add(g.fig10_landmarks, ss, t);
      break;
  }
  return cells;
}

std::string figureCsv(Figure f, const std::vector<CellSummary>& cells, const StudyMeta& meta) {
  const int n_max = meta.config.max_order;
  std::string s =
      "figure,level,angle_noise,noise_scale,noise_law,max_surface_m,range_max_m,stops,step_m,scans_"
      "per_stop,"
      "landmarks,sigma_s_m,sigma_theta_deg,trials,detected_landmarks";
  for (PositionEstimator e : kPositionOrder) {
    const std::string p = std::string("pos_") + toString(e) + "_";
    s += "," + p + "samples," + p + "missing," + p + "bias_m," + p + "mean_radial_m," + p +
         "mean_tangential_m," + p + "variance_m2," + p + "rmse_m," + p + "error_q25_m," + p +
         "error_median_m," + p + "error_q75_m," + p + "radial_q25_m," + p + "radial_median_m," + p +
         "radial_q75_m";
  }
  // Ratio statistics of one test set: quartiles, median's standard error, mean and its standard
  // error.
  auto statColumns = [](const std::string& p) {
    return "," + p + "_q25," + p + "_median," + p + "_q75," + p + "_median_se," + p + "_mean," + p +
           "_mean_se";
  };
  auto statValues = [](const SampleStats& x) {
    return "," + num(x.q.q25) + "," + num(x.q.median) + "," + num(x.q.q75) + "," +
           num(x.median_se) + "," + num(x.mean) + "," + num(x.mean_se);
  };
  const std::array<std::string, kTestSets> set_names = {"ratio", "ratioc", "ratio1"};
  for (Estimator e : kRatioEstimators) {
    const std::string p = std::string(toString(e)) + "_";
    s += "," + p + "runs," + p + "failed";
    for (Rule rule : kRuleOrder) {
      const std::string r = p + (rule == Rule::aic ? "" : "pars_");
      for (const auto& set : set_names) s += statColumns(r + set);
      for (int n = 0; n <= n_max; ++n) s += "," + r + "order" + std::to_string(n) + "_rate";
    }
  }
  for (const auto& set : set_names) s += statColumns("ceiling_" + set);
  s += "\n";
  const TrialConfig& c = meta.config;
  for (const CellSummary& x : cells) {
    s += std::string(toString(f)) + "," + toString(c.level) + "," + toString(c.angle_noise) + "," +
         num(c.noise_scale) + "," + toString(c.noise_law) + "," + num(c.placement.max_surface_m) +
         "," + num(c.sensor.range_max_m) + "," + std::to_string(c.path.stops) + "," +
         num(c.path.step_m) + "," + std::to_string(c.path.scans_per_stop) + "," +
         std::to_string(x.cell.landmarks) + "," + num(x.cell.sigma_s_m) + "," +
         num(rad2deg(x.cell.sigma_theta_rad)) + "," + std::to_string(x.trials) + "," +
         num(x.detected_landmarks);
    for (PositionEstimator e : kPositionOrder) {
      const PositionSummary& p = positionOf(x, e);
      s += "," + std::to_string(p.samples) + "," + std::to_string(p.missing) + "," + num(p.bias_m) +
           "," + num(p.mean_radial_m) + "," + num(p.mean_tangential_m) + "," + num(p.variance_m2) +
           "," + num(p.rmse_m) + "," + num(p.error_m.q25) + "," + num(p.error_m.median) + "," +
           num(p.error_m.q75) + "," + num(p.radial_m.q25) + "," + num(p.radial_m.median) + "," +
           num(p.radial_m.q75);
    }
    for (Estimator e : kRatioEstimators) {
      const RatioSummary& r = ratioOf(x, e);
      s += "," + std::to_string(r.runs) + "," + std::to_string(r.failures);
      for (Rule rule : kRuleOrder) {
        for (std::size_t set = 0; set < kTestSets; ++set)
          s += statValues(r.rules[static_cast<std::size_t>(rule)].ratio[set]);
        for (int n = 0; n <= n_max; ++n) s += "," + num(orderRate(r, n, rule));
      }
    }
    for (std::size_t set = 0; set < kTestSets; ++set) s += statValues(x.ceiling[set]);
    s += "\n";
  }
  return s;
}

}  // namespace lidarcal::studies
