// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Private to the figures (figures.cpp, figure_gnuplot.cpp, figure_summary.cpp): numbers as text,
// the cells' statistics by estimator, gnuplot blocks and panels, Markdown tables.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/stats_util.hpp"
#include "studies/figures.hpp"

namespace lidarcal::studies {
/// Number with %.*g, "NaN" when not finite (gnuplot and spreadsheets read both).
inline std::string num(double v, int digits = 6) {
  if (!std::isfinite(v)) return "NaN";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

/// Number for a Markdown table, "-" when not finite.
inline std::string cellText(double v, int digits = 3) {
  return std::isfinite(v) ? num(v, digits) : "-";
}

inline std::string percent(double v) { return std::isfinite(v) ? num(100.0 * v, 3) + " %" : "-"; }

inline bool same(double a, double b) {
  return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(b));
}

/// The summary of the cell with these parameters, or nullptr.
inline const CellSummary* find(const std::vector<CellSummary>& cells, int L, double sigma_s_m,
                               double sigma_theta_deg) {
  for (const auto& c : cells)
    if (c.cell.landmarks == L && same(c.cell.sigma_s_m, sigma_s_m) &&
        same(rad2deg(c.cell.sigma_theta_rad), sigma_theta_deg))
      return &c;
  return nullptr;
}

inline const RatioSummary& ratioOf(const CellSummary& c, Estimator e) {
  return c.ratio[static_cast<std::size_t>(e)];
}
inline const PositionSummary& positionOf(const CellSummary& c, PositionEstimator e) {
  return c.position[static_cast<std::size_t>(e)];
}

/// The MSE-ratio statistics of an estimator (AIC unless said: the rule the paper uses).
inline const SampleStats& ratioStats(const CellSummary& c, Estimator e, Rule rule = Rule::aic,
                                     TestSet set = TestSet::beams) {
  return ratioOf(c, e).rules[static_cast<std::size_t>(rule)].ratio[static_cast<std::size_t>(set)];
}

inline double orderRate(const RatioSummary& r, int order, Rule rule = Rule::aic) {
  const std::size_t ok = r.runs - r.failures;
  const auto& counts = r.rules[static_cast<std::size_t>(rule)].order_counts;
  if (ok == 0 || order < 0 || static_cast<std::size_t>(order) >= counts.size()) return kNaN;
  return static_cast<double>(counts[static_cast<std::size_t>(order)]) / static_cast<double>(ok);
}

inline const std::vector<Estimator> kRatioEstimators = {Estimator::closed_form, Estimator::joint,
                                                        Estimator::oracle};
inline const std::vector<PositionEstimator> kPositionOrder = {PositionEstimator::triangulation,
                                                              PositionEstimator::joint};
inline const std::vector<Rule> kRuleOrder = {Rule::aic, Rule::aic_parsimonious};

/// Whether an estimator ran in any cell (the joint refinement does not with --no-joint): plots
/// leave out what did not run, as gnuplot cannot draw a panel without a single point.
inline bool ran(const std::vector<CellSummary>& cells, Estimator e) {
  return std::any_of(cells.begin(), cells.end(),
                     [&](const CellSummary& c) { return ratioOf(c, e).runs > 0; });
}
inline std::vector<Estimator> ranEstimators(const std::vector<CellSummary>& cells) {
  std::vector<Estimator> out;
  for (Estimator e : kRatioEstimators)
    if (ran(cells, e)) out.push_back(e);
  return out;
}
inline std::vector<PositionEstimator> ranPositionEstimators(const std::vector<CellSummary>& cells) {
  std::vector<PositionEstimator> out = {PositionEstimator::triangulation};
  if (ran(cells, Estimator::joint)) out.push_back(PositionEstimator::joint);
  return out;
}

inline std::string estimatorLabel(Estimator e) {
  switch (e) {
    case Estimator::closed_form:
      return "closed form (paper)";
    case Estimator::joint:
      return "joint refinement";
    case Estimator::oracle:
      return "oracle (true distances)";
  }
  return "";
}

inline std::string positionLabel(PositionEstimator e) {
  return e == PositionEstimator::triangulation ? "triangulation (paper)" : "joint refinement";
}

inline std::string settingsText(const StudyMeta& m) {
  const TrialConfig& c = m.config;
  std::string s;
  s += "level " + std::string(toString(c.level)) + ", angle noise on the " +
       toString(c.angle_noise) + ", " + std::to_string(c.path.stops) + " stops " +
       num(c.path.step_m * 100.0, 3) + " cm apart, " + std::to_string(c.path.scans_per_stop) +
       " scans per stop, noise " + num(c.noise_scale, 3) +
       " x the paper's (beta = " + num(0.05 * c.noise_scale, 3) + " alpha), n_max " +
       std::to_string(c.max_order) + ", " + std::to_string(m.trials) +
       " trials per cell (joint refinement on the first " +
       std::to_string(std::min(m.joint_trials, m.trials)) + "), seed " + std::to_string(m.seed) +
       ", landmarks " + num(c.placement.min_surface_m, 3) + "-" +
       num(c.placement.max_surface_m, 3) + " m from every stop, noise law " +
       toString(c.noise_law) + ", reading window " + num(c.sensor.range_min_m, 3) + "-" +
       num(c.sensor.range_max_m, 3) + " m";
  return s;
}

// gnuplot

/// An inline data block: `$name << EOD` ... `EOD`.
inline std::string block(const std::string& name, const std::vector<std::vector<double>>& rows) {
  std::string s = "$" + name + " << EOD\n";
  for (const auto& r : rows) {
    for (std::size_t i = 0; i < r.size(); ++i) s += (i ? " " : "") + num(r[i]);
    s += "\n";
  }
  return s + "EOD\n";
}

inline std::string preamble(const std::string& file, int width, int height) {
  return "set terminal pngcairo size " + std::to_string(width) + "," + std::to_string(height) +
         " font \"DejaVu Sans,10\"\nset output \"" + file +
         "\"\nset datafile missing \"NaN\"\nset grid\n"
         "set key top left font \",9\"\nset format y \"%g\"\n";
}

inline std::string colour(std::size_t i) {
  static const char* kColours[] = {"#1b9e77", "#d95f02", "#7570b3", "#e7298a",
                                   "#66a61e", "#e6ab02", "#a6761d", "#666666"};
  return kColours[i % 8];
}

/// One multiplot panel: `series` = (data block, using, title, style).
struct Series {
  std::string data, columns, title, style;
};
inline std::string panel(const std::string& title, const std::string& settings,
                         const std::vector<Series>& series) {
  std::string s = "set title \"" + title + "\"\n" + settings;
  std::string plot;
  for (const auto& x : series)
    plot += (plot.empty() ? "plot " : ", \\\n     ") + x.data + " using " + x.columns + " " +
            x.style + " title \"" + x.title + "\"";
  return s + (plot.empty() ? "" : plot + "\n") + "unset logscale\n";
}

/// "set yrange [a:b]" spanning whole decades around the finite positive values (one scale for
/// every panel of a figure, so the estimators compare at a glance).
inline std::string decadeRange(const std::vector<double>& values) {
  double lo = 1e300, hi = 0.0;
  for (double v : values)
    if (std::isfinite(v) && v > 0.0) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  if (!(hi > 0.0)) return "set yrange [*:*]\n";
  return "set yrange [" + num(std::pow(10.0, std::floor(std::log10(lo)))) + ":" +
         num(std::pow(10.0, std::ceil(std::log10(hi)))) + "]\n";
}

inline std::string sigmaText(double sigma_s_m) {
  return "σ_s " + num(sigma_s_m * 100.0, 3) + " cm";
}
inline std::string thetaText(double deg) { return "σ_θ " + num(deg, 3) + "°"; }

// Markdown

inline std::string table(const std::vector<std::string>& header,
                         const std::vector<std::vector<std::string>>& rows) {
  std::string s = "|";
  for (const auto& h : header) s += " " + h + " |";
  s += "\n|";
  for (std::size_t i = 0; i < header.size(); ++i) s += "---|";
  s += "\n";
  for (const auto& r : rows) {
    s += "|";
    for (const auto& c : r) s += " " + c + " |";
    s += "\n";
  }
  return s;
}

/// Verdict word for a claim.
inline std::string verdict(bool agrees) { return agrees ? "**agrees**" : "**differs**"; }

inline double rmse(const CellSummary* c, PositionEstimator e) {
  return c ? positionOf(*c, e).rmse_m : kNaN;
}
inline double medianRatio(const CellSummary* c, Estimator e) {
  return c ? ratioStats(*c, e).q.median : kNaN;
}
inline double meanRatio(const CellSummary* c, Estimator e) {
  return c ? ratioStats(*c, e).mean : kNaN;
}

}  // namespace lidarcal::studies
