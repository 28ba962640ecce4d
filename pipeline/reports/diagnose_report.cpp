// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/reports/diagnose_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "common/pose2.hpp"
#include "io/atomic_file.hpp"
#include "io/gnuplot.hpp"
#include "pipeline/reports/words.hpp"

namespace lidarcal::pipeline {
namespace {

using ojson = nlohmann::ordered_json;
using diagnosis::DiagnosisResult;
using diagnosis::ResidualRecord;

std::string fmt(double v, int digits) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

std::string pfmt(double p) {
  if (!std::isfinite(p)) return "-";
  char buf[64];
  if (p < 1e-3)
    std::snprintf(buf, sizeof buf, "%.1e", p);
  else
    std::snprintf(buf, sizeof buf, "%.3f", p);
  return buf;
}

/// One variable the residuals are plotted against.
struct Variable {
  std::string file, title, label;
  std::function<double(const ResidualRecord&)> x;
  double bin = 0.0;  ///< bin width (0: integer groups)
};

std::vector<Variable> variables(diagnosis::DiagnoseMode mode) {
  std::vector<Variable> v;
  v.push_back({"range", "range", "range (predicted true distance or mean reading) [m]",
               [](const ResidualRecord& r) { return r.range_m; }, 0.25});
  v.push_back({"incidence", "incidence angle", "incidence angle on the surface [deg]",
               [](const ResidualRecord& r) { return rad2deg(r.incidence_rad); }, 5.0});
  if (mode == diagnosis::DiagnoseMode::sequence)
    v.push_back({"lateral", "position across the pole",
                 "beam's miss distance from the centre / radius (0 centre, +-1 edge)",
                 [](const ResidualRecord& r) { return r.lateral; }, 0.1});
  else
    v.push_back({"edge", "depth discontinuity", "0: inside a surface, 1: at a depth discontinuity",
                 [](const ResidualRecord& r) { return r.edge ? 1.0 : 0.0; }, 0.0});
  v.push_back({"time", "scan index (time)", "scan index",
               [](const ResidualRecord& r) { return r.time; }, 0.0});
  v.push_back({"bearing", "beam angle", "beam angle in the sensor frame [deg]",
               [](const ResidualRecord& r) { return rad2deg(r.bearing_rad); }, 10.0});
  v.push_back({"group", mode == diagnosis::DiagnoseMode::sequence ? "landmark" : "wall",
               mode == diagnosis::DiagnoseMode::sequence ? "landmark id"
                                                         : "wall line (0: not on a fitted wall)",
               [](const ResidualRecord& r) { return static_cast<double>(r.group); }, 0.0});
  if (mode == diagnosis::DiagnoseMode::sequence)
    v.push_back({"stop", "stop", "stop index",
                 [](const ResidualRecord& r) { return static_cast<double>(r.stop); }, 0.0});
  return v;
}

/// Per bin of x: mean residual (mm) and standard deviation of z, for one set of records.
std::map<double, std::array<double, 4>> binned(const std::vector<ResidualRecord>& rs,
                                               const Variable& v, double time_bin) {
  std::map<double, std::array<double, 4>> acc;  // sum r, sum z, sum z^2, n
  for (const auto& r : rs) {
    const double x = v.x(r);
    if (!std::isfinite(x) || !std::isfinite(r.z)) continue;
    const double w = v.file == "time" ? time_bin : v.bin;
    const double key = w > 0.0 ? (std::floor(x / w) + 0.5) * w : x;
    auto& a = acc[key];
    a[0] += 1000.0 * r.residual_m;
    a[1] += r.z;
    a[2] += r.z * r.z;
    a[3] += 1.0;
  }
  std::map<double, std::array<double, 4>> out;
  for (const auto& [k, a] : acc) {
    if (a[3] < 5) continue;
    const double mz = a[1] / a[3];
    out[k] = {a[0] / a[3], mz, std::sqrt(std::max(a[2] / a[3] - mz * mz, 0.0)), a[3]};
  }
  return out;
}

std::string scatter(const std::vector<ResidualRecord>& rs, const Variable& v,
                    std::size_t max_points) {
  std::ostringstream s;
  s.precision(6);
  const std::size_t stride = std::max<std::size_t>(1, rs.size() / max_points);
  for (std::size_t i = 0; i < rs.size(); i += stride) {
    const double x = v.x(rs[i]);
    if (std::isfinite(x)) s << x << ' ' << 1000.0 * rs[i].residual_m << '\n';
  }
  return s.str();
}

std::string histogram(const std::vector<ResidualRecord>& rs) {
  std::map<int, double> h;
  double n = 0.0;
  for (const auto& r : rs) {
    if (!std::isfinite(r.z)) continue;
    ++h[static_cast<int>(std::floor(std::clamp(r.z, -10.0, 10.0) / 0.25))];
    n += 1.0;
  }
  std::ostringstream s;
  for (const auto& [k, c] : h) s << (k + 0.5) * 0.25 << ' ' << c / (n * 0.25) << '\n';
  return s.str();
}

// ---- report.md, section by section ----

void writeDataLine(std::ostream& md, const DiagnosisResult& r, const DiagnosisSource& src) {
  const bool seq = r.mode == diagnosis::DiagnoseMode::sequence;
  md << "# lidarcal diagnosis\n\n";
  md << "Data: `" << src.data.string() << "`" << (src.sensor.empty() ? "" : " (" + src.sensor + ")")
     << ", **" << toString(r.mode) << "** mode: " << plural(r.scans, "scan");
  if (seq)
    md << " at " << plural(r.stops, "stop")
       << (src.selection.empty() ? "" : " (" + src.selection + ")") << ", "
       << plural(r.landmarks, "landmark");
  else
    md << (src.selection.empty() ? "" : " (" + src.selection + ")") << ", "
       << plural(r.landmarks, "wall line");
  md << ", " << plural(r.readings, "reading");
  if (seq && src.beside_pole_readings > 0)
    md << " (" << src.beside_pole_readings
       << " of them beside a pole, between it and the background: mixed-pixel candidates the "
          "detector leaves out)";
  md << ".";
  if (!src.model.empty()) md << " Readings first corrected with `" << src.model << "`.";
  md << "\n\n";
}

void writeVerdict(std::ostream& md, const DiagnosisResult& r) {
  md << "## Verdict\n\n**Primary cause: `" << r.primary_cause << "`.** " << r.decision << ".\n\n";
  if (!r.extended_parameters.empty()) {
    md << "Held-out gain of the extended model: " << fmt(r.gain_heldout_nats_per_point, 4)
       << " nats per point; delta AIC " << fmt(r.gain_delta_aic, 1) << ".\n\n";
  }
}

void writeWallTable(std::ostream& md, const std::vector<diagnosis::WallLine>& walls) {
  md << "\nWall lines fitted to the beam means (the geometric reference):\n\n| wall | normal [deg] "
        "| distance [m] | beams from [deg] | to [deg] | beams | RMS about the model [mm] "
        "|\n|---|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < walls.size(); ++i) {
    const auto& w = walls[i];
    md << "| " << i + 1 << " | " << fmt(rad2deg(w.normal_rad), 2) << " | " << fmt(w.distance_m, 4)
       << " | " << fmt(rad2deg(w.first_angle_rad), 1) << " | " << fmt(rad2deg(w.last_angle_rad), 1)
       << " | " << w.bins << " | " << fmt(1000.0 * w.rms_m, 2) << " |\n";
  }
}

void writeBaseline(std::ostream& md, const DiagnosisResult& r, const DiagnosisSource& src) {
  const bool seq = r.mode == diagnosis::DiagnoseMode::sequence;
  md << "## Baseline (the published model: Alhashimi et al. 2016 and 2021)\n\n";
  md << "- bias f(d) = ";
  for (std::size_t i = 0; i < r.baseline.bias.alpha.size(); ++i) {
    const double a = r.baseline.bias.alpha[i];
    md << (i ? (a < 0 ? " - " : " + ") : (a < 0 ? "-" : "")) << fmt(std::abs(a), 5)
       << (i ? " d" : "") << (i > 1 ? "^" + std::to_string(i) : "");
  }
  md << "\n- noise sigma = " << fmt(r.baseline.noise.sigma_e, 6)
     << " f(d)^2 (Alhashimi et al. 2016, eq. 1)";
  md << ": " << fmt(1000.0 * r.baseline.noise.stddev(1.0, r.baseline.bias), 1) << " mm at 1 m, "
     << fmt(1000.0 * r.baseline.noise.stddev(3.0, r.baseline.bias), 1) << " mm at 3 m\n";
  if (seq)
    md << "- landmark radius " << fmt(r.baseline_radius_m, 4) << " m ("
       << (r.radius_known ? "given" : "estimated") << "), sighting bearing noise "
       << fmt(rad2deg(r.baseline_sigma_theta_rad), 3)
       << " deg, stop headings at the commanded ones\n";
  for (const auto& [k, v] : r.baseline_extra)
    md << "- " << k << ": " << (v == std::round(v) ? fmt(v, 0) : fmt(v, 5)) << "\n";
  md << "- held-out log-likelihood " << fmt(r.baseline_heldout_nats_per_point, 4)
     << " nats per point\n";
  if (!seq && !src.walls.empty()) writeWallTable(md, src.walls);
}

void writeBattery(std::ostream& md, const DiagnosisResult& r) {
  md << "\n## What the baseline gets wrong: discrepancy statistics\n\n";
  md << "Each statistic on the data against " << r.replicas
     << " parametric bootstrap replicas (the same geometry simulated from the fitted baseline and "
        "refitted); p-value from the "
        "replicas (Student-t predictive), effect size in replica standard deviations.\n\n";
  md << "| statistic | against | value | replicas: mean | sd | effect size | p-value "
        "|\n|---|---|---|---|---|---|---|\n";
  for (const auto& d : r.battery)
    md << "| `" << d.name << "` | " << d.variable << " | " << fmt(d.value, 3) << " | "
       << fmt(d.replica_mean, 3) << " | " << fmt(d.replica_sd, 3) << " | " << fmt(d.effect_size, 1)
       << " | " << pfmt(d.p_value) << " |\n";
  md << "\n<details><summary>How each statistic is computed</summary>\n\n";
  for (const auto& d : r.battery) md << "- `" << d.name << "`: " << d.description << "\n";
  md << "\n</details>\n";
}

/// The sequence was refined with the motion prior (continuous recording): no stop has a pose
/// prior of its own to hold out.
bool motionPrior(const DiagnosisResult& r) {
  const auto it = r.baseline_extra.find("motion_prior");
  return it != r.baseline_extra.end() && it->second > 0.5;
}

void writeCandidates(std::ostream& md, const DiagnosisResult& r) {
  const bool seq = r.mode == diagnosis::DiagnoseMode::sequence;
  md << "\n## Candidate effects\n\n";
  md << "Each effect added to the baseline and fitted; held-out log-likelihood gain per point ("
     << r.folds << " folds by scan"
     << (!seq             ? ", wall beams leave-one-out"
         : motionPrior(r) ? ""
                          : ", odometry leave-one-stop-out")
     << "), its one-sided p-value, Holm-adjusted across the candidates; significant = adjusted p < "
        "alpha with a positive gain"
     << "; `quantisation` (readings on a grid): the p of its held-out gain alone, every other "
        "model scored on the readings "
        "spread over their grid cells"
     << ".\n\n";
  md << "| effect | held-out gain [nats/pt] | se | p | Holm p | delta AIC | params | significant | "
        "identifiable | estimates | note |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : r.candidates) {
    std::string est;
    for (const auto& [k, v] : c.estimates) est += (est.empty() ? "" : ", ") + k + " = " + fmt(v, 5);
    md << "| `" << toString(c.effect) << "` | "
       << (c.applicable ? fmt(c.heldout_gain_nats_per_point, 5) : "-") << " | "
       << (c.applicable ? fmt(c.heldout_gain_se, 5) : "-") << " | " << pfmt(c.p_value) << " | "
       << pfmt(c.p_holm) << " | " << (c.applicable ? fmt(c.delta_aic, 1) : "-") << " | "
       << c.parameters << " | " << (c.significant ? "**yes**" : "no") << " | "
       << (c.identifiable ? "yes" : "no") << " | " << est << " | " << c.note << " |\n";
  }
}

void writeTails(std::ostream& md, const DiagnosisResult& r) {
  const auto& t = r.tails;
  if (!t.fitted) return;
  md << "\n## What the tails are made of\n\n";
  md << "A contamination mixture (diagnosis/tails.hpp): pooled, a fraction "
     << fmt(t.pooled_fraction, 4) << " of readings " << fmt(t.pooled_wide_scale, 3)
     << " times as wide as the core, held-out gain " << fmt(t.pooled_gain_nats_per_point, 4)
     << " +- " << fmt(t.pooled_gain_se, 4)
     << " nats per reading over the Gaussian baseline; with its probability depending on the "
        "covariates, a further "
     << fmt(t.explained_gain_nats_per_point, 4) << " +- " << fmt(t.explained_gain_se, 4)
     << ". Cause: `" << t.cause << "`.\n\n";
  md << "| covariate | effect | coefficient | unique held-out gain [nats/pt] | se | Holm p | share "
        "| significant |\n"
        "|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : t.covariates)
    md << "| " << c.covariate << " | `" << toString(c.effect) << "` | " << fmt(c.coefficient, 3)
       << " | " << fmt(c.unique_gain_nats_per_point, 5) << " | " << fmt(c.unique_gain_se, 5)
       << " | " << pfmt(c.p_holm) << " | " << fmt(100.0 * c.share, 1) << " % | "
       << (c.significant ? "**yes**" : "no") << " |\n";
  md << "\nTail readings (posterior sums) by class of beam, of " << fmt(t.tail_readings, 1) << ":";
  for (const auto& [k, v] : t.tail_readings_by_class)
    md << " " << k << " " << fmt(v, 1) << " of " << fmt(t.readings_by_class.at(k), 0) << ";";
  md << "\n\n| beam [deg] | range [m] | incidence [deg] | intensity | edge | readings | tail "
        "fraction | fitted pi | class |\n"
        "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& b : t.top_beams)
    md << "| " << fmt(rad2deg(b.bearing_rad), 1) << " | " << fmt(b.range_m, 3) << " | "
       << (std::isfinite(b.incidence_rad) ? fmt(rad2deg(b.incidence_rad), 1) : "-") << " | "
       << (std::isfinite(b.intensity) ? fmt(b.intensity, 1) : "-") << " | "
       << (b.edge ? "yes" : "no") << " | " << b.readings << " | " << fmt(b.tail_fraction, 3)
       << " | " << fmt(b.tail_probability, 3) << " | " << b.cls << " |\n";
  md << "\nUnder the pooled contamination:";
  for (const auto& [k, v] : t.robust) md << " " << k << " = " << fmt(v, 4) << ";";
  md << "\n";
}

void writeExtended(std::ostream& md, const DiagnosisResult& r) {
  md << "\n## The extended model\n\n";
  if (r.extended_parameters.empty() && r.scene_keys.empty()) {
    md << "No effect was named: the baseline stays.\n";
    return;
  }
  md << "Effect `" << r.primary_cause << "`:";
  for (const auto& [k, v] : r.extended_parameters) md << " " << k << " = " << fmt(v, 5) << ";";
  md << "\n\nScene keys that simulate it (`lidarcal simulate`, docs/FORMAT.md):\n\n";
  for (const auto& [k, v] : r.scene_keys) md << "- `" << k << "` = " << fmt(v, 6) << "\n";
  md << "\n| simulation | KS distance of standardised residuals to the data | median abs "
        "ln(variance ratio) per group | groups |\n|---|---|---|---|\n";
  md << "| baseline | " << fmt(r.closeness_baseline.ks_distance, 4) << " | "
     << fmt(r.closeness_baseline.variance_ratio_median_abs_log, 3) << " | "
     << r.closeness_baseline.groups << " |\n";
  md << "| extended | " << fmt(r.closeness_extended.ks_distance, 4) << " | "
     << fmt(r.closeness_extended.variance_ratio_median_abs_log, 3) << " | "
     << r.closeness_extended.groups << " |\n";
  if (r.calibration_mse_ratio_baseline > 0.0)
    md << "\nAgainst the truth: MSE ratio (raw MSE / corrected MSE, higher is better; Alhashimi et "
          "al. 2021, eq. 31) of the calibration "
       << fmt(r.calibration_mse_ratio_baseline, 1) << " with the baseline, "
       << fmt(r.calibration_mse_ratio_extended, 1) << " with the extended model.\n";
}

// ---- Plots ----

/// The scatter's vertical range: the central 99 % of the residuals (a few gross ones would
/// flatten the rest), mm.
std::pair<double, double> residualRange(const std::vector<ResidualRecord>& measured) {
  double ylo = -1.0, yhi = 1.0;
  std::vector<double> mm;
  for (const auto& x : measured)
    if (std::isfinite(x.residual_m)) mm.push_back(1000.0 * x.residual_m);
  if (mm.size() > 10) {
    std::sort(mm.begin(), mm.end());
    ylo = mm[mm.size() / 200];
    yhi = mm[mm.size() - 1 - mm.size() / 200];
    const double pad = 0.1 * (yhi - ylo) + 1e-3;
    ylo -= pad;
    yhi += pad;
  }
  return {ylo, yhi};
}

/// binned_<v>.dat: x, measured mean residual and z spread, simulated spreads, simulated baseline
/// mean.
std::string binnedTable(const DiagnosisResult& r, const Variable& v, double time_bin) {
  std::ostringstream b;
  b.precision(6);
  const auto m = binned(r.measured, v, time_bin), sb = binned(r.simulated_baseline, v, time_bin),
             se = binned(r.simulated_extended, v, time_bin);
  for (const auto& [k, a] : m) {
    b << k << ' ' << a[0] << ' ' << a[2];
    auto ib = sb.find(k);
    b << ' ' << (ib != sb.end() ? fmt(ib->second[2], 5) : "NaN");
    auto ie = se.find(k);
    b << ' ' << (ie != se.end() ? fmt(ie->second[2], 5) : "NaN");
    b << ' ' << (ib != sb.end() ? fmt(ib->second[0], 5) : "NaN") << '\n';
  }
  return b.str();
}

/// The gnuplot commands of one variable's residual plot (scatter and means, spreads).
void residualPlot(std::ostream& gp, const Variable& v, double ylo, double yhi) {
  gp << "set output \"residuals_" << v.file
     << ".png\"\nset multiplot layout 2,1 title \"Residuals against " << v.title
     << ": measured vs simulated\"\n";
  gp << "set xlabel \"" << v.label
     << "\"\nset ylabel \"residual [mm] (central 99 %)\"\nset key top right\nset yrange [" << ylo
     << ":" << yhi << "]\n";
  gp << "plot \"scatter_" << v.file
     << ".dat\" using 1:2 with points pt 7 ps 0.2 lc rgb \"#bbbbbb\" title \"measured readings\", "
     << "\"binned_" << v.file
     << ".dat\" using 1:2 with linespoints lw 2 pt 7 lc rgb \"#cc3311\" title \"measured, mean\", "
     << "\"binned_" << v.file
     << ".dat\" using 1:6 with linespoints lw 2 pt 6 dt 2 lc rgb \"#0077bb\" title \"simulated "
        "baseline, mean\"\n";
  gp << "set ylabel \"sd of standardised residual\"\nset yrange [*:*]\n";
  gp << "plot \"binned_" << v.file
     << ".dat\" using 1:3 with linespoints lw 2 pt 7 lc rgb \"#cc3311\" title \"measured\", "
     << "\"binned_" << v.file
     << ".dat\" using 1:4 with linespoints lw 2 pt 6 lc rgb \"#0077bb\" title \"simulated "
        "baseline\", "
     << "\"binned_" << v.file
     << ".dat\" using 1:5 with linespoints lw 2 pt 4 lc rgb \"#009944\" title \"simulated "
        "extended\", "
     << "1 with lines dt 2 lc rgb \"black\" notitle\n";
  gp << "unset multiplot\n";
}

/// The distribution plot's data files and gnuplot commands.
void distributionPlot(const std::filesystem::path& dir, const DiagnosisResult& r,
                      std::ostream& gp) {
  io::writeTextAtomically(dir / "hist_measured.dat", histogram(r.measured));
  io::writeTextAtomically(dir / "hist_baseline.dat", histogram(r.simulated_baseline));
  io::writeTextAtomically(dir / "hist_extended.dat", histogram(r.simulated_extended));
  gp << "set terminal pngcairo size 900,600 font \"DejaVu Sans,10\"\nset output "
        "\"residual_distribution.png\"\n"
     << "set title \"Standardised residuals under the baseline: measured vs simulated\"\nset "
        "xlabel \"z\"\n"
     << "set ylabel \"density\"\nset logscale y\nset yrange [1e-5:1]\nset key top right\n"
     << "plot \"hist_measured.dat\" using 1:2 with steps lw 2 lc rgb \"#cc3311\" title "
        "\"measured\", "
     << "\"hist_baseline.dat\" using 1:2 with steps lw 2 lc rgb \"#0077bb\" title \"simulated "
        "baseline\", "
     << "\"hist_extended.dat\" using 1:2 with steps lw 2 lc rgb \"#009944\" title \"simulated "
        "extended\", "
     << "exp(-x*x/2)/sqrt(2*pi) with lines dt 2 lc rgb \"black\" title \"N(0,1)\"\nunset logscale "
        "y\n";
}

/// Writes the plots' data and plots.gp, runs gnuplot and adds the Plots section.
void writePlots(const std::filesystem::path& dir, const DiagnosisResult& r, std::ostream& md) {
  const auto vars = variables(r.mode);
  double tmax = 1.0;
  for (const auto& x : r.measured) tmax = std::max(tmax, x.time);
  const double time_bin = std::max(1.0, std::ceil(tmax / 40.0));
  const auto [ylo, yhi] = residualRange(r.measured);
  std::ostringstream gp;
  gp << "set terminal pngcairo size 900,760 font \"DejaVu Sans,10\"\nset grid\n";
  for (const auto& v : vars) {
    io::writeTextAtomically(dir / ("scatter_" + v.file + ".dat"), scatter(r.measured, v, 12000));
    io::writeTextAtomically(dir / ("binned_" + v.file + ".dat"), binnedTable(r, v, time_bin));
    residualPlot(gp, v, ylo, yhi);
  }
  distributionPlot(dir, r, gp);
  io::writeTextAtomically(dir / "plots.gp", gp.str());
  std::string why;
  const bool plotted = io::runGnuplot(dir, "plots.gp", &why);
  md << "\n## Plots\n\n";
  if (!plotted) {
    md << "(" << why << ")\n";
    return;
  }
  md << "Top: residuals of the measured readings under the baseline (grey), their mean per bin "
        "(red) and the same for a "
        "simulated replica of the baseline (blue). Bottom: spread of the standardised residuals "
        "per bin, measured and "
        "simulated from the baseline and from the extended model (1 = the model's noise).\n\n";
  for (const auto& v : vars)
    md << "![residuals against " << v.title << "](residuals_" << v.file << ".png)\n\n";
  md << "![distribution of the standardised residuals](residual_distribution.png)\n";
}

}  // namespace

void writeDiagnosis(const std::filesystem::path& dir, const DiagnosisResult& r,
                    const DiagnosisSource& src) {
  io::writeTextAtomically(dir / "diagnosis.json", diagnosisJson(r, src).dump(2) + "\n");
  std::ostringstream md;
  writeDataLine(md, r, src);
  if (!r.status.ok()) {
    md << "**Not diagnosed: " << r.status.name() << ".** " << r.status.message << "\n";
    io::writeTextAtomically(dir / "report.md", md.str());
    return;
  }
  writeVerdict(md, r);
  writeBaseline(md, r, src);
  writeBattery(md, r);
  writeCandidates(md, r);
  writeTails(md, r);
  writeExtended(md, r);
  writePlots(dir, r, md);
  if (!src.command.empty()) md << "\nProduced by `" << src.command << "`.\n";
  io::writeTextAtomically(dir / "report.md", md.str());
}

}  // namespace lidarcal::pipeline
