// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/reports/fleet_report.hpp"
#include "io/json_number.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <utility>

#include "common/stats_util.hpp"
#include "io/gnuplot.hpp"

namespace lidarcal::pipeline {
namespace {

nlohmann::json numbers(const std::vector<double>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (double x : v) a.push_back(io::jsonNumber<nlohmann::json>(x));
  return a;
}

nlohmann::json biasJson(const std::vector<calibration::BiasAt>& bias) {
  nlohmann::json a = nlohmann::json::array();
  for (const calibration::BiasAt& b : bias)
    a.push_back({{"distance_m", b.distance_m},
                 {"bias_m", io::jsonNumber<nlohmann::json>(b.bias_m)},
                 {"se_m", io::jsonNumber<nlohmann::json>(b.se_m)},
                 {"inside_fitted_range", b.inside},
                 {"noise_sigma_m", io::jsonNumber<nlohmann::json>(b.noise_m)}});
  return a;
}

nlohmann::json testJson(const calibration::FleetTest& t) {
  nlohmann::json j = {{"tested", t.tested}};
  if (!t.tested) {
    j["why_not"] = t.why_not;
    return j;
  }
  j["distances_m"] = t.distances_m;
  j["difference_m"] = numbers(t.difference_m);
  if (!t.z.empty()) j["z"] = numbers(t.z);
  j["statistic"] = io::jsonNumber<nlohmann::json>(t.statistic);
  j["dof"] = t.dof;
  j["p"] = io::jsonNumber<nlohmann::json>(t.p);
  j["p_holm"] = io::jsonNumber<nlohmann::json>(t.p_holm);
  j["flagged"] = t.flagged;
  return j;
}

nlohmann::json sensorJson(const calibration::FleetRow& r) {
  const CalibrationModel& m = r.current.model;
  nlohmann::json j = {{"sensor", r.current.sensor},
                      {"date", r.current.date},
                      {"model", r.current.source},
                      {"method", m.method},
                      {"order", m.model.bias.order()},
                      {"alpha", m.model.bias.alpha},
                      {"status", toString(m.status.code)},
                      {"message", m.status.message},
                      {"warnings", m.warnings},
                      {"bias", biasJson(r.bias)}};
  j["fitted_range_m"] = m.fitted_range_m
                            ? nlohmann::json{m.fitted_range_m->first, m.fitted_range_m->second}
                            : nlohmann::json(nullptr);
  j["previous"] = r.previous ? nlohmann::json{{"date", r.previous->date},
                                              {"model", r.previous->source},
                                              {"bias", biasJson(r.previous_bias)}}
                             : nlohmann::json(nullptr);
  j["moved"] = testJson(r.moved);
  j["outlier"] = testJson(r.outlier);
  nlohmann::json flags = nlohmann::json::array();
  if (r.moved.flagged) flags.push_back("moved");
  if (r.outlier.flagged) flags.push_back("outlier");
  j["flags"] = flags;
  return j;
}

/// v with `places` decimals ("-" when not finite), with a sign when `sign`.
std::string decimals(double v, int places, bool sign = false) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, sign ? "%+.*f" : "%.*f", places, v);
  return buf;
}

/// v with 6 significant digits ("-" when not finite).
std::string general(double v) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string mm(double metres) { return decimals(1000.0 * metres, 1, true); }

std::string pValue(double p) { return p < 1e-4 ? "< 0.0001" : decimals(p, 4); }

std::string testCell(const calibration::FleetTest& t, const std::string& size) {
  if (!t.tested) return "not tested";
  return std::string(t.flagged ? "**" : "") + size + ", p_Holm " + pValue(t.p_holm) +
         (t.flagged ? "**" : "");
}

std::string tableRow(const calibration::FleetRow& r) {
  const CalibrationModel& m = r.current.model;
  std::string row =
      "| " + r.current.sensor + " | " + (r.current.date.empty() ? "-" : r.current.date) + " |";
  for (const calibration::BiasAt& b : r.bias)
    row += " " + mm(b.bias_m) + " ± " + decimals(1000.0 * b.se_m, 1) +
           (b.inside ? "" : " (outside)") + " |";
  const calibration::BiasAt& middle = r.bias[r.bias.size() / 2];
  row += " " + decimals(1000.0 * middle.noise_m, 1) + " |";
  double largest = 0.0;
  for (double d : r.moved.difference_m) largest = std::max(largest, std::abs(d));
  row += " " + testCell(r.moved, "largest change " + decimals(1000.0 * largest, 1) + " mm") + " |";
  row += " " + testCell(r.outlier, decimals(r.outlier.statistic, 1) + " SE from the median") + " |";
  std::string flags = r.moved.flagged ? "moved" : "";
  if (r.outlier.flagged) flags += std::string(flags.empty() ? "" : ", ") + "outlier";
  row += " " + (flags.empty() ? std::string("-") : "**" + flags + "**") + " |";
  const std::string status = toString(m.status.code);
  row += " " + status +
         (m.warnings.empty() ? "" : ", " + std::to_string(m.warnings.size()) + " warning(s)") +
         " |";
  return row + "\n";
}

/// The fleet plot: every sensor's bias curve (left) and its difference from the fleet's median
/// curve (right: the pointwise median of the current calibrations over a common distance grid,
/// where three quarters of them reach), each curve drawn over its own fitted range only.
class FleetPlot {
 public:
  explicit FleetPlot(const calibration::FleetSummary& s) : summary_(s) {
    double lo = kInf, hi = -kInf;
    for (const calibration::FleetRow& r : s.rows) {
      const auto [a, b] = range(r.current.model);
      lo = std::min(lo, a);
      hi = std::max(hi, b);
    }
    for (int i = 0; i <= kSteps && lo < hi; ++i) grid_.push_back(lo + (hi - lo) * i / kSteps);
    for (double d : grid_) {
      std::vector<double> bias;
      for (const calibration::FleetRow& r : s.rows)
        if (inside(r.current.model, d)) bias.push_back(r.current.model.model.bias(d) - d);
      // Where a quarter of the curves end, the median would jump with who is left: none there.
      median_.push_back(4 * bias.size() >= 3 * s.rows.size() ? median(bias) : kNaN);
    }
  }

  /// A curve in both panels; only the first curve of a title is named in the key.
  void add(const CalibrationModel& m, const std::string& style, const std::string& title) {
    const std::string name = "$c" + std::to_string(curves_++);
    data_ += name + " << EOD\n";
    for (std::size_t i = 0; i < grid_.size(); ++i) {
      const double d = grid_[i], b = inside(m, d) ? 1000.0 * (m.model.bias(d) - d) : kNaN;
      data_ += general(d) + " " + general(b) + " " + general(b - 1000.0 * median_[i]) + "\n";
    }
    data_ += "EOD\n";
    const bool named = titles_.insert(title).second;
    const std::string key = named ? "title " + io::gnuplotString(title) : "notitle";
    left_ += (left_.empty() ? "plot " : ", \\\n     ") + name + " using 1:2 with lines " + style +
             " " + key;
    right_ += (right_.empty() ? "plot " : ", \\\n     ") + name + " using 1:3 with lines " + style +
              " notitle";
  }

  std::string script(const std::string& plot_file) const {
    std::string gp =
        "set terminal svg size 1400,600 font \"DejaVu Sans,11\" background rgb \"white\"\nset "
        "output " +
        io::gnuplotString(plot_file) +
        "\nset datafile missing \"-\"\nset grid\nset key top left noenhanced\n" +
        "set xlabel \"true distance d (m)\"\n" + data_ + "$median << EOD\n";
    for (std::size_t j = 0; j < summary_.config.distances_m.size(); ++j)
      gp += general(summary_.config.distances_m[j]) + " " +
            general(1000.0 * summary_.median_bias_m[j]) + " " +
            general(1000.0 * summary_.robust_sd_m[j]) + "\n";
    gp += "EOD\nset multiplot layout 1,2 title \"" + std::to_string(summary_.rows.size()) +
          " sensors, latest calibrations, each over its fitted range\"\n";
    const std::string median_series =
        "$median using 1:2:3 with yerrorbars pt 7 ps 1 lc rgb \"black\" "
        "title \"fleet median ± robust spread\"";
    gp += "set title \"bias\"\nset ylabel \"bias f(d) - d (mm)\"\n" + left_ +
          (left_.empty() ? "plot " : ", \\\n     ") + median_series + "\n";
    gp +=
        "set title \"difference from the fleet's median curve\"\nset ylabel \"bias - fleet median "
        "(mm)\"\n" +
        (right_.empty() ? std::string("plot 0 notitle") : right_) + "\nunset multiplot\n";
    return gp;
  }

 private:
  static constexpr int kSteps = 80;
  std::pair<double, double> range(const CalibrationModel& m) const {
    if (m.fitted_range_m) return *m.fitted_range_m;
    return {summary_.config.distances_m.front(), summary_.config.distances_m.back()};
  }
  bool inside(const CalibrationModel& m, double d) const {
    const auto [lo, hi] = range(m);
    return d >= lo && d <= hi;
  }
  const calibration::FleetSummary& summary_;
  std::vector<double> grid_, median_;
  std::string data_, left_, right_;
  std::set<std::string> titles_;
  std::size_t curves_ = 0;
};

}  // namespace

nlohmann::json fleetJson(const calibration::FleetSummary& s) {
  nlohmann::json j;
  j["format"] = "lidarcal-fleet/1";
  j["settings"] = {{"distances_m", s.config.distances_m},
                   {"alpha", s.config.alpha},
                   {"multiple_testing", "holm"},
                   {"min_fleet", s.config.min_fleet}};
  j["fleet"] = {{"sensors", s.rows.size()},
                {"median_bias_m", numbers(s.median_bias_m)},
                {"robust_sd_m", numbers(s.robust_sd_m)},
                {"sensors_at_distance", s.sensors_at}};
  j["sensors"] = nlohmann::json::array();
  for (const calibration::FleetRow& r : s.rows) j["sensors"].push_back(sensorJson(r));
  j["flagged"] = s.flagged;
  return j;
}

std::string fleetMarkdown(const calibration::FleetSummary& s, const std::string& plot_file) {
  std::string md = "# Fleet report\n\n" + std::to_string(s.rows.size()) + " sensors; ";
  md += s.flagged.empty() ? "none flagged.\n\n"
                          : "flagged: **" + std::to_string(s.flagged.size()) + "**:";
  for (std::size_t i = 0; i < s.flagged.size(); ++i)
    md += std::string(i ? ", " : " ") + s.flagged[i];
  if (!s.flagged.empty()) md += ".\n\n";
  if (!plot_file.empty()) md += "![every sensor's bias against distance](" + plot_file + ")\n\n";
  md += "| sensor | date |";
  for (double d : s.config.distances_m) md += " bias at " + general(d) + " m (mm ± SE) |";
  md += " noise σ at " + general(s.config.distances_m[s.config.distances_m.size() / 2]) +
        " m (mm) | against its previous calibration | against the fleet | flags | status |\n|";
  for (std::size_t i = 0; i < s.config.distances_m.size() + 7; ++i) md += "---|";
  md += "\n";
  for (const calibration::FleetRow& r : s.rows) md += tableRow(r);
  md += "\nFleet median bias (robust spread, sensors):";
  for (std::size_t j = 0; j < s.config.distances_m.size(); ++j)
    md += std::string(j ? ";" : "") + " " + general(s.config.distances_m[j]) +
          " m: " + mm(s.median_bias_m[j]) + " mm (" + decimals(1000.0 * s.robust_sd_m[j], 1) +
          " mm, " + std::to_string(s.sensors_at[j]) + ")";
  md += ".\n\n";
  std::string warnings;
  for (const calibration::FleetRow& r : s.rows) {
    for (const std::string& w : r.current.model.warnings)
      warnings += "- " + r.current.sensor + ": " + w + "\n";
    if (!r.current.model.status.ok())
      warnings += "- " + r.current.sensor + ": " + r.current.model.status.message + "\n";
  }
  if (!warnings.empty()) md += "## Warnings\n\n" + warnings + "\n";
  md +=
      "## How to read it\n\n"
      "Bias is f(d) − d, the reading's error at true distance d, with its standard error from the "
      "model's "
      "covariance; `(outside)` marks a distance beyond the calibration's fitted range (not "
      "compared). "
      "**Against its previous calibration**: Wald's test of the change in bias over the distances "
      "inside both "
      "fitted ranges, with both calibrations' covariances (chi-square). **Against the fleet**: at "
      "each distance the "
      "sensor's bias against the median of the other sensors, scaled by their robust spread (MAD) "
      "beyond their own "
      "estimation noise plus the sensor's own standard error (Student's t), Bonferroni over the "
      "distances. Each "
      "family of tests is Holm-adjusted over the sensors: a sensor is flagged when its adjusted "
      "p-value is below " +
      general(s.config.alpha) + ", so the chance that any unchanged sensor is flagged is at most " +
      general(s.config.alpha) + " per family.\n";
  return md;
}

std::string fleetGnuplot(const calibration::FleetSummary& s, const std::string& plot_file) {
  FleetPlot plot(s);
  for (const calibration::FleetRow& r : s.rows)
    if (!(r.moved.flagged || r.outlier.flagged))
      plot.add(r.current.model, "lw 1 lc rgb \"#b0b0b0\"", "sensors not flagged");
  static const char* kColours[] = {"#d95f02", "#7570b3", "#e7298a", "#66a61e",
                                   "#e6ab02", "#a6761d", "#1b9e77"};
  std::size_t flagged = 0;
  for (const calibration::FleetRow& r : s.rows) {
    if (!(r.moved.flagged || r.outlier.flagged)) continue;
    const std::string colour = std::string("lc rgb \"") + kColours[flagged++ % 7] + "\"";
    plot.add(r.current.model, "lw 3 " + colour, r.current.sensor + " " + r.current.date);
    if (r.previous)
      plot.add(r.previous->model, "lw 2 dt 2 " + colour,
               r.current.sensor + " " + r.previous->date + " (previous)");
  }
  return plot.script(plot_file);
}

}  // namespace lidarcal::pipeline
