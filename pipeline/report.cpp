// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/report.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "calibration/filtering.hpp"
#include "calibration/inversion.hpp"
#include "calibration/joint_refinement.hpp"
#include "io/atomic_file.hpp"
#include "pipeline/gnuplot.hpp"
#include "pipeline/model_text.hpp"
#include "pipeline/papers.hpp"
#include "pipeline/words.hpp"

namespace lidarcal::pipeline {
namespace {

std::string noiseText(const NoiseModel& n, const BiasPolynomial& f) {
  switch (n.kind) {
    case NoiseKind::squared:
      return "sigma(d) = " + fixed(n.sigma_e, 5) + " f(d)^2 (" +
             std::string(papers::kTriangulation) +
             ", eq. 1): " + fixed(1000 * n.stddev(1.0, f), 1) + " mm at 1 m, " +
             fixed(1000 * n.stddev(3.0, f), 1) + " mm at 3 m";
    case NoiseKind::polynomial:
      return "sigma(d) = |" + polynomialText(n.beta) + "| (" + std::string(papers::kLandmarks) +
             ", eq. 3)";
    case NoiseKind::constant:
      return "sigma = " + fixed(n.sigma_e, 4) + " m";
    default:
      return toString(n.kind);
  }
}

struct PlotData {
  std::string distance, curve, noise, raw, corrected, circles, stops, histogram, truth;
  std::size_t readings = 0;  ///< rows of `distance`
  FittedRange fitted;
};

/// Readings drawn on the scatter plots at most: more only overplot and make the SVG files large
/// (about 100 bytes per point).
constexpr std::size_t kMaxScatterPoints = 2500;

/// Counts of raw and corrected errors in common bins over the central 99 % of both.
std::string histogram(std::vector<double> raw, std::vector<double> cor) {
  std::vector<double> all = raw;
  all.insert(all.end(), cor.begin(), cor.end());
  if (all.size() < 2) return {};
  std::sort(all.begin(), all.end());
  const double lo = all[all.size() / 200], hi = all[all.size() - 1 - all.size() / 200];
  if (!(hi > lo)) return {};
  constexpr int kBins = 50;
  const double width = (hi - lo) / kBins;
  std::vector<std::size_t> nr(kBins, 0), nc(kBins, 0);
  auto add = [&](const std::vector<double>& v, std::vector<std::size_t>& n) {
    for (double e : v) {
      const int b = static_cast<int>(std::floor((e - lo) / width));
      if (b >= 0 && b < kBins)
        ++n[static_cast<std::size_t>(b)];
      else if (e == hi)
        ++n[kBins - 1];
    }
  };
  add(raw, nr);
  add(cor, nc);
  std::ostringstream o;
  o.precision(6);
  for (int b = 0; b < kBins; ++b)
    o << lo + (b + 0.5) * width << ' ' << nr[static_cast<std::size_t>(b)] << ' '
      << nc[static_cast<std::size_t>(b)] << '\n';
  return o.str();
}

std::string circleLines(double x, double y, double r) {
  std::ostringstream o;
  o.precision(6);
  for (int i = 0; i <= 72; ++i) {
    const double a = 2.0 * kPi * i / 72.0;
    o << x + r * std::cos(a) << ' ' << y + r * std::sin(a) << '\n';
  }
  return o.str() + "\n";
}

/// `v` as an ostream of precision 6 writes it (printf's %.6g), then `end`: the readings' table
/// has a row per reading, which std::to_chars writes several times faster than a stream.
void appendG6(std::string& out, double v, char end) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 6);
  out.append(buf, r.ptr);
  out.push_back(end);
}

/// The readings behind the distance, residual, histogram and noise plots, one at a time.
struct ReadingTally {
  /// as `correct` does (the fit's readings lie inside its range)
  std::optional<calibration::ReadingCorrector> correct;
  // 0.25 m bins of the true distance: sum of d, readings
  std::map<int, std::pair<double, int>> bins;
  std::map<int, double> bin_sum2;
  std::vector<double> raw_errors, corrected_errors;
  double d_min = std::numeric_limits<double>::infinity(), d_max = 0.0;

  explicit ReadingTally(const CalibrationModel& m) {
    try {
      correct.emplace(calibration::readingCorrector(m, calibration::InversionMethod::ls,
                                                    calibration::kDefaultOutside));
    } catch (const std::invalid_argument&) {
    }
  }
  /// Adds reading y at true distance d; returns the corrected reading (NaN where the model has no
  /// distance for it).
  double add(PlotData& p, const CalibrationModel& m, double d, double y) {
    d_min = std::min(d_min, d);
    d_max = std::max(d_max, d);
    const double c = correct ? (*correct)(y).range_m : std::nan("");
    appendG6(p.distance, d, ' ');
    appendG6(p.distance, y, ' ');
    appendG6(p.distance, c, '\n');
    ++p.readings;
    raw_errors.push_back(y - d);
    if (std::isfinite(c)) corrected_errors.push_back(c - d);
    const double r = y - m.model.bias(d);
    const int bin = static_cast<int>(std::floor(d / 0.25));
    bins[bin].first += d;
    bins[bin].second += 1;
    bin_sum2[bin] += r * r;
    return c;
  }
  /// The fitted range, the noise per bin, the fitted curve and the histogram.
  void finish(PlotData& p, const CalibrationModel& m) {
    std::ostringstream noise, curve;
    noise.precision(6);
    curve.precision(6);
    if (d_max > 0.0) p.fitted = {d_min, d_max};
    // what the fit saw
    if (m.fitted_range_m) p.fitted = {m.fitted_range_m->first, m.fitted_range_m->second};
    for (const auto& [bin, v] : bins)
      if (v.second >= 5)
        noise << v.first / v.second << ' ' << std::sqrt(bin_sum2[bin] / v.second) << ' '
              << m.model.noise.stddev(v.first / v.second, m.model.bias) << '\n';
    // The fitted curve over the plotted range only (beyond it the polynomial is extrapolated).
    const auto [lo, hi] = plotRange(p.fitted);
    const int steps = 200;
    for (int i = 0; i <= steps; ++i) {
      const double d = lo + (hi - lo) * i / steps;
      curve << d << ' ' << m.model.bias(d) << ' ' << d << '\n';
    }
    p.noise = noise.str();
    p.curve = curve.str();
    p.histogram = histogram(std::move(raw_errors), std::move(corrected_errors));
  }
};

PlotData plotData(const LandmarkObservations& obs, const CalibrationModel& m,
                  const std::vector<Cylinder>& truth) {
  PlotData p;
  ReadingTally tally(m);
  std::ostringstream raw, cor, circles, stops, true_circles;
  for (auto* o : {&raw, &cor, &stops}) o->precision(6);
  std::map<int, const CalibratedLandmark*> lm;
  for (const auto& l : m.landmarks)
    if (l.status == "ok") lm[l.id] = &l;
  std::map<std::size_t, std::size_t> first_scan_of_stop;
  for (const auto& s : obs.sightings) {
    auto f = first_scan_of_stop.find(s.stop);
    if (f == first_scan_of_stop.end() || s.scan < f->second) first_scan_of_stop[s.stop] = s.scan;
  }
  for (const auto& s : obs.sightings) {
    auto it = lm.find(s.landmark);
    if (it == lm.end() || s.stop >= m.stop_poses.size() || s.stop >= obs.commanded.size()) continue;
    const Pose2& est = m.stop_poses[s.stop];
    const Pose2& cmd = obs.commanded[s.stop];
    const bool map_scan = first_scan_of_stop[s.stop] == s.scan;  // one scan per stop on the map
    for (const auto& b : s.beams) {
      const double d =
          calibration::rayCircleDistance(est.x_m, est.y_m, est.yaw_rad + b.angle_rad,
                                         it->second->x_m, it->second->y_m, it->second->radius_m);
      if (!std::isfinite(d)) continue;
      const double c = tally.add(p, m, d, b.range_m);
      if (!map_scan) continue;
      const double ar = cmd.yaw_rad + b.angle_rad;
      raw << cmd.x_m + b.range_m * std::cos(ar) << ' ' << cmd.y_m + b.range_m * std::sin(ar)
          << '\n';
      if (std::isfinite(c)) {
        const double ac = est.yaw_rad + b.angle_rad;
        cor << est.x_m + c * std::cos(ac) << ' ' << est.y_m + c * std::sin(ac) << '\n';
      }
    }
  }
  tally.finish(p, m);
  for (const auto& [id, l] : lm) circles << circleLines(l->x_m, l->y_m, l->radius_m);
  for (std::size_t k = 0; k < m.stop_poses.size(); ++k)
    stops << m.stop_poses[k].x_m << ' ' << m.stop_poses[k].y_m << ' ' << k << '\n';
  for (const auto& c : truth) true_circles << circleLines(c.x_m, c.y_m, c.radius_m);
  p.raw = raw.str();
  p.corrected = cor.str();
  p.circles = circles.str();
  p.stops = stops.str();
  p.truth = true_circles.str();
  return p;
}

/// The plots of a calibration against reference measurements: the readings whose true distance
/// the reference gives (or, for a span's walls, the fit places), and on the map one scan per stop
/// of them, raw and corrected, at the commanded poses.
PlotData knownPlotData(const std::vector<calibration::KnownReading>& known,
                       const LandmarkObservations& obs, const CalibrationModel& m) {
  PlotData p;
  ReadingTally tally(m);
  std::ostringstream raw, cor, stops;
  for (auto* o : {&raw, &cor, &stops}) o->precision(6);
  std::map<std::size_t, std::size_t> first_scan_of_stop;
  for (const auto& r : known) {
    auto f = first_scan_of_stop.find(r.stop);
    if (f == first_scan_of_stop.end() || r.scan < f->second) first_scan_of_stop[r.stop] = r.scan;
  }
  for (const auto& r : known) {
    const double c = tally.add(p, m, r.d_m, r.y_m);
    if (first_scan_of_stop[r.stop] != r.scan || r.stop >= obs.commanded.size()) continue;
    const Pose2& cmd = obs.commanded[r.stop];
    const double a = cmd.yaw_rad + r.angle_rad;
    raw << cmd.x_m + r.y_m * std::cos(a) << ' ' << cmd.y_m + r.y_m * std::sin(a) << '\n';
    if (std::isfinite(c))
      cor << cmd.x_m + c * std::cos(a) << ' ' << cmd.y_m + c * std::sin(a) << '\n';
  }
  tally.finish(p, m);
  for (std::size_t k = 0; k < obs.commanded.size(); ++k)
    stops << obs.commanded[k].x_m << ' ' << obs.commanded[k].y_m << ' ' << k << '\n';
  p.raw = raw.str();
  p.corrected = cor.str();
  p.stops = stops.str();
  return p;
}

/// The plots against distance: raw error with the fitted bias, error before and after
/// correction (the readings sampled as `sample` says), and noise.
void distancePlots(std::ostringstream& g, const std::string& sample, const std::string& shown,
                   bool reference) {
  g << R"GP(set arrow 1 from fit_min, graph 0 to fit_min, graph 1 nohead dt 3 lc rgb "#666666"
set arrow 2 from fit_max, graph 0 to fit_max, graph 1 nohead dt 3 lc rgb "#666666"
set output "distance.svg"
set title "Raw range error against the )GP"
    << (reference ? "true distance the reference measurements give"
                  : "distance estimated from the landmarks")
    << R"GP( (dotted: fitted range)"
set xlabel "estimated true distance d [m]"
set ylabel "raw reading - d [m]"
plot "distance.dat")GP"
    << sample
    << R"GP( using 1:($2-$1) with points pt 7 ps 0.3 lc rgb "#8899bb" title "readings on )GP"
    << (reference ? "the measured targets" : "landmarks") << shown << R"GP(", \
     "curve.dat" using 1:($2-$1) with lines lw 2 lc rgb "#cc3311" title "fitted bias f(d) - d", \
     0 with lines dt 2 lc rgb "black" title "ideal (no error)"
set output "residuals.svg"
set title "Error before and after correction against the estimated distance"
set ylabel "reading - d [mm]"
plot "distance.dat")GP"
    << sample
    << R"GP( using 1:(1000*($2-$1)) with points pt 7 ps 0.3 lc rgb "#cc3311" title "raw)GP" << shown
    << R"GP(", \
     "distance.dat")GP"
    << sample
    << R"GP( using 1:(1000*($3-$1)) with points pt 7 ps 0.3 lc rgb "#009944" title "corrected)GP"
    << shown << R"GP(", \
     0 with lines dt 2 lc rgb "black" title "no error"
set output "noise.svg"
set title "Noise against distance"
set ylabel "standard deviation of the reading [mm]"
plot "noise.dat" using 1:($2*1000) with points pt 7 ps 1 lc rgb "#0077bb" title "measured (RMS residual, 0.25 m bins)", \
     "noise.dat" using 1:($3*1000) with lines lw 2 lc rgb "#cc3311" title "noise model"
unset arrow 1
unset arrow 2
)GP";
}

/// The map: landmarks (estimated, and true when known), raw and corrected points, the stops.
void mapPlot(std::ostringstream& g, bool truth, bool reference) {
  g << R"GP(set terminal svg size 900,900 font "DejaVu Sans,11" background rgb "white"
set output "map.svg"
set title ")GP"
    << (reference ? "Points on the measured targets, raw and corrected"
                  : "Landmarks with raw and corrected points")
    << R"GP(, one scan per stop"
set autoscale x
set xlabel "x [m]"
set ylabel "y [m]"
set size ratio -1
plot )GP";
  if (!reference)
    g << "\"circles.dat\" using 1:2 with lines lw 2 lc rgb \"#999999\" title \"landmarks "
         "(estimated)\", \\\n";
  if (truth)
    g << "     \"truth.dat\" using 1:2 with lines lw 1 dt 2 lc rgb \"black\" title \"landmarks "
         "(truth)\", \\\n";
  g << R"GP(     "raw.dat" using 1:2 with points pt 2 ps 0.6 lc rgb "#cc3311" title "raw", \
     "corrected.dat" using 1:2 with points pt 6 ps 0.6 lc rgb "#009944" title "corrected", \
     "stops.dat" using 1:2 with points pt 7 ps 0.8 lc rgb "#0044aa" title "stops (numbered)", \
     "stops.dat" using 1:2:(int($3) % label_every == 0 ? sprintf("%d", $3) : "") with labels offset 0.8,0.8 font ",9" tc rgb "#0044aa" notitle
)GP";
}

/// The gnuplot script of the report. Distance plots share the x range of the fitted data;
/// legends sit outside the plotting area; every label_every-th of `stops` stops is numbered.
std::string reportScript(const FittedRange& fitted, bool histogram, bool truth, std::size_t stops,
                         std::size_t readings, bool reference) {
  const auto [lo, hi] = plotRange(fitted);
  // An even sample of the readings on the scatter plots (all of them stay in distance.dat).
  const std::size_t every =
      std::max<std::size_t>(1, (readings + kMaxScatterPoints - 1) / kMaxScatterPoints);
  const std::string sample = every == 1 ? std::string() : " every " + std::to_string(every);
  const std::string shown =
      every == 1 ? std::string() : " (1 in " + std::to_string(every) + " shown)";
  std::ostringstream g;
  g.precision(6);
  g << "set terminal svg size 1000,650 font \"DejaVu Sans,11\" background rgb \"white\"\n"
       "set grid\n"
       "set key outside below horizontal\n"
       "set xrange ["
    << lo << ":" << hi << "]\n"
    << "fit_min = " << fitted.min_m << "\nfit_max = " << fitted.max_m
    << "\n"
    // About 20 stop numbers on the map at most (a long recording has a stop per scan).
    << "label_every = " << std::max<std::size_t>(1, (stops + 19) / 20) << "\n";
  distancePlots(g, sample, shown, reference);
  if (histogram)
    g << R"GP(set output "histogram.svg"
set title "Error of the readings on landmarks, before and after correction"
set autoscale x
set xlabel "reading - estimated distance [mm]"
set ylabel "readings"
plot "histogram.dat" using (1000*$1):2 with histeps lw 2 lc rgb "#cc3311" title "raw", \
     "histogram.dat" using (1000*$1):3 with histeps lw 2 lc rgb "#009944" title "corrected"
)GP";
  mapPlot(g, truth, reference);
  return g.str();
}

std::string comparisonRow(const ComparedModel& c) {
  const auto& l = c.evaluation.landmarks;
  const auto& a = c.evaluation.all;
  return "| " + c.name + " | " + std::to_string(c.model.model.bias.order()) + " | " +
         fixed(l.mse_ratio, 2) + " | " + fixed(a.mse_ratio, 2) + " | " +
         fixed(1000 * std::sqrt(l.mse_corrected_m2), 2) + " | " + fixed(a.nmse_corrected, 5) +
         " |\n";
}

}  // namespace

std::pair<double, double> plotRange(const FittedRange& fitted) {
  const double margin = std::max(0.1, 0.1 * (fitted.max_m - fitted.min_m));
  return {std::max(0.0, fitted.min_m - margin), fitted.max_m + margin};
}

namespace {

/// The model in words: bias with its standard errors, noise, bearing noise, range, notes.
void writeModelSection(std::ostringstream& md, const CalibrationModel& m,
                       const FittedRange& fitted) {
  md << "## The calibrated model\n\n";
  md << "- method: **" << m.method << "**, bias " << orderText(m) << " (chosen by " << m.order_rule
     << ")\n";
  md << "- bias: reading = f(d) = " << polynomialWithErrors(m) << "  (d = true distance in metres"
     << (coefficientErrors(m).empty() || !std::isfinite(coefficientErrors(m)[0])
             ? ""
             : "; +- one standard error")
     << ")\n";
  md << "- noise: " << noiseText(m.model.noise, m.model.bias) << "\n";
  if (m.method != "reference") {  // a fit to measured distances estimates no bearing noise
    md << "- bearing noise sigma_theta = " << fixed(rad2deg(m.sigma_theta_rad), 3) << " deg";
    if (m.method == "joint")
      md << "; stop poses moved by " << fixed(1000 * m.pose_scatter_m, 1) << " mm and "
         << fixed(rad2deg(m.heading_scatter_rad), 2) << " deg (RMS) from the commanded ones";
    md << "\n";
  }
  if (m.fitted_range_m)
    md << "- fitted on readings at true distances from " << fixed(m.fitted_range_m->first, 2)
       << " to " << fixed(m.fitted_range_m->second, 2)
       << " m (the beams' distances to the surfaces they hit; the sensor reads up "
       << "to " << fixed(m.model.range_max_m, 1)
       << " m). Beyond them `lidarcal correct` continues the correction at "
       << "its slope at the edge, without a step or a kink, and marks those points (field "
          "`correction` = 2, with "
          "their standard error in `correction_se`; docs/FORMAT.md). `--outside keep`, `drop` or "
          "`extrapolate` "
          "(the polynomial itself) choose otherwise.\n";
  else if (fitted.max_m > 0.0)
    md << "- fitted on landmark readings at estimated distances from " << fixed(fitted.min_m, 2)
       << " to " << fixed(fitted.max_m, 2) << " m (the sensor reads up to "
       << fixed(m.model.range_max_m, 1) << " m)\n";
  if (!m.status.message.empty()) md << "- note: " << m.status.message << "\n";
  for (const auto& w : m.warnings) md << "- **warning**: " << w << "\n";
}

/// What the raw sensor reads at a few true distances, with the error and its standard error.
void writeErrorTable(std::ostringstream& md, const CalibrationModel& m, const FittedRange& fitted) {
  using papers::kTriangulation;
  md << "\nWhat the raw sensor reads at a few true distances, and the error it makes";
  if (fitted.max_m > 0.0) md << " (rows outside the fitted range are extrapolated, marked *)";
  md << ":\n\n";
  md << "| true distance | raw reading | error (+- curve SE) | predictive 95 % interval | noise (1 "
        "sigma) | data |\n"
        "|---|---|---|---|---|---|\n";
  const double last = std::min(m.model.range_max_m, std::max(5.0, fitted.max_m));
  for (double d : {0.25, 0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 15.0, 20.0, 25.0, 30.0,
                   40.0, 50.0, 60.0, 80.0}) {
    if (d > last) break;
    if (d < m.model.range_min_m) continue;
    const bool inside = fitted.max_m <= 0.0 || fitted.contains(d);
    md << "| " << fixed(d, 2) << " m" << (inside ? "" : " *") << " | " << fixed(m.model.bias(d), 3)
       << " m | " << fixed(1000 * (m.model.bias(d) - d), 1, true)
       << (std::isfinite(biasError(m, d)) ? " +- " + fixed(1000 * biasError(m, d), 1)
                                          : std::string())
       << " mm | "
       << (std::isfinite(biasError(m, d))
               ? "+- " + fixed(1000 * predictiveHalfWidth(m, d, 0.95), 1) + " mm"
               : "-")
       << " | " << fixed(1000 * m.model.noise.stddev(d, m.model.bias), 1) << " mm | "
       << (inside ? "fitted" : "extrapolated") << " |\n";
  }
  md << "\nThe curve SE says how well the data pin the polynomial down; the predictive interval is "
        "where the "
        "sensor's error at a distance the fit did not see lies with 95 % probability: "
     << discrepancyText(m) << " (" << papers::kDiscrepancy << "; " << papers::kReml << "; "
     << papers::kPredictionInterval << "). A single reading adds its noise.\n";
  md << "\n`lidarcal correct` inverts f for every point (" << kTriangulation
     << ", eq. 30) and moves it along its beam.\n";
}

/// One row of the written scans' table: returns, RMS error raw and corrected, MSE ratio.
std::string writtenRow(const std::string& name, const calibration::RangeComparison& c) {
  if (c.n == 0) return "| " + name + " | 0 | - | - | - |\n";
  return "| " + name + " | " + std::to_string(c.n) + " | " +
         fixed(1000 * std::sqrt(c.mse_raw_m2), 2) + " | " +
         fixed(1000 * std::sqrt(c.mse_corrected_m2), 2) + " | " + fixed(c.mse_ratio, 2) + " |\n";
}

/// The MSE ratios against the truth, when there is one.
void writeTruthSection(std::ostringstream& md, const ReportInputs& in) {
  using papers::kLandmarks;
  using papers::kTriangulation;
  if (in.compared.empty()) return;
  md << "\n## Against the truth\n\n" << in.truth_note << "\n\n";
  md << "The MSE ratio is the raw readings' mean squared error divided by the corrected ones' ("
     << kLandmarks << ", eq. 31): higher is better, 1 means no gain.\n\n";
  const calibration::Evaluation& ours = in.compared.front().evaluation;
  md << "The corrected scans as written:\n\n| returns on | returns | raw RMS error [mm] | "
        "corrected RMS error [mm] | "
        "MSE ratio |\n|---|---|---|---|---|\n";
  md << writtenRow("landmarks", ours.landmarks) << writtenRow("walls", ours.walls)
     << writtenRow("all", ours.all)
     << writtenRow(std::string("beyond the fitted range (--outside ") +
                       calibration::toString(in.outside) + ")",
                   ours.beyond);
  if (ours.lost > 0)
    md << "\n"
       << plural(ours.lost, "raw return") << " had no corrected distance and are not scored.\n";
  md << "\nEvery model under the same rule:\n\n";
  md << "| model | order | MSE ratio, landmarks | MSE ratio, all returns | RMS error after, "
        "landmarks [mm] | "
        "normalised MSE after ("
     << kTriangulation << ", eq. 31) |\n|---|---|---|---|---|---|\n";
  md << "| raw readings | - | 1.00 | 1.00 | "
     << fixed(1000 * std::sqrt(ours.landmarks.mse_raw_m2), 2) << " | "
     << fixed(ours.all.nmse_raw, 5) << " |\n";
  for (const auto& c : in.compared) md << comparisonRow(c);
}

/// The plot data, the gnuplot script and the plots (or why there are none).
void writePlotsSection(std::ostringstream& md, const std::filesystem::path& dir,
                       const CalibrationModel& m, const std::optional<PlotData>& p,
                       const FittedRange& fitted) {
  using papers::kLandmarks;
  std::string why;
  bool plotted = false;
  if (p) {
    io::writeTextAtomically(dir / "distance.dat", p->distance);
    io::writeTextAtomically(dir / "curve.dat", p->curve);
    io::writeTextAtomically(dir / "noise.dat", p->noise);
    io::writeTextAtomically(dir / "raw.dat", p->raw);
    io::writeTextAtomically(dir / "corrected.dat", p->corrected);
    io::writeTextAtomically(dir / "circles.dat", p->circles);
    io::writeTextAtomically(dir / "stops.dat", p->stops);
    if (!p->histogram.empty()) io::writeTextAtomically(dir / "histogram.dat", p->histogram);
    if (!p->truth.empty()) io::writeTextAtomically(dir / "truth.dat", p->truth);
    const std::size_t stops =
        m.stop_poses.empty()
            ? static_cast<std::size_t>(std::count(p->stops.begin(), p->stops.end(), '\n'))
            : m.stop_poses.size();
    io::writeTextAtomically(dir / "plots.gp",
                            reportScript(fitted, !p->histogram.empty(), !p->truth.empty(), stops,
                                         p->readings, p->circles.empty()));
    plotted = runGnuplot(dir, "plots.gp", &why);
  }
  md << "\n## Plots\n\n";
  if (plotted) {
    md << "![raw readings against estimated distance](distance.svg)\n\n";
    md << "![error before and after correction against distance](residuals.svg)\n\n";
    if (!p->histogram.empty()) md << "![error before and after correction](histogram.svg)\n\n";
    md << "![noise against distance](noise.svg)\n\n";
    md << "![landmark map with numbered stops, raw and corrected points"
       << (p->truth.empty() ? "" : ", true landmarks") << " (" << kLandmarks
       << ", Fig. 13)](map.svg)\n";
  } else {
    md << "(" << (p ? why : std::string("no plot data")) << ")\n";
  }
}

void writeOrderSection(std::ostringstream& md, const CalibrationModel& m) {
  md << "\n## Order selection\n\n| order | alpha | AIC | BIC | validation MSE [mm^2] | test MSE "
        "[mm^2] |\n|---|---|---|---|---|---|\n";
  for (const auto& o : m.orders)
    md << "| " << o.order << " | " << polynomialText(o.alpha) << " | " << fixed(o.aic, 1) << " | "
       << fixed(o.bic, 1) << " | "
       << (std::isfinite(o.validation_mse_m2) ? fixed(1e6 * o.validation_mse_m2, 2) : "-") << " | "
       << (std::isfinite(o.test_mse_m2) ? fixed(1e6 * o.test_mse_m2, 2) : "-") << " |\n";
  md << "\nAIC picks order " << m.order_aic;
  if (m.order_validation >= 0) md << ", held-out validation order " << m.order_validation;
  md << ".\n";
}

/// The seeds' noise estimators side by side and the noise-exponent test.
void writeNoiseSection(std::ostringstream& md, const CalibrationModel& m) {
  using papers::kLandmarks;
  using papers::kTriangulation;
  const auto& nf = m.noise_fits;
  md << "\n## Noise estimators side by side\n\n";
  md << "| estimator | result |\n|---|---|\n";
  md << "| " << kLandmarks << ", polynomial noise, ML | sigma(d) = |"
     << polynomialText(nf.alhashimi2021_beta) << "| |\n";
  md << "| " << kTriangulation
     << ", closed form (eqs. 21-26) | f = " << polynomialText(nf.alhashimi2016_cf_alpha)
     << ", sigma_e = " << fixed(nf.alhashimi2016_cf_sigma_e, 5) << " |\n";
  md << "| " << kTriangulation
     << ", full ML (eqs. 18-20) | f = " << polynomialText(nf.alhashimi2016_ml_alpha)
     << ", sigma_e = " << fixed(nf.alhashimi2016_ml_sigma_e, 5) << " |\n";
  for (const auto& [name, reason] : nf.unavailable) {
    const std::string label =
        name == "alhashimi2021_beta"          ? std::string(kLandmarks) + ", polynomial noise"
        : name == "alhashimi2016_closed_form" ? std::string(kTriangulation) + ", closed form"
        : name == "alhashimi2016_ml"          ? std::string(kTriangulation) + ", full ML"
                                              : std::string("noise-exponent test");
    md << "| " << label << " | not available: " << reason << " |\n";
  }
  if (nf.exponent_best >= 0) {
    md << "\nThe noise-exponent test of " << kTriangulation << " (eqs. 10-15) on "
       << nf.exponent_batches
       << " constant-distance batches (one beam over the scans of a stop): log-likelihood of y = f "
          "+ f^k e for k = 0..3: ";
    for (int k = 0; k < 4; ++k)
      md << (k ? ", " : "") << fixed(nf.exponent_loglik[static_cast<std::size_t>(k)], 1);
    md << "; best k = **" << nf.exponent_best << "**.\n";
  }
}

void writeLandmarksSection(std::ostringstream& md, const CalibrationModel& m) {
  md << "\n## Landmarks\n\n| id | x [m] | y [m] | radius [m] | stops | status "
        "|\n|---|---|---|---|---|---|\n";
  for (const auto& l : m.landmarks)
    md << "| " << l.id << " | " << fixed(l.x_m, 3) << " | " << fixed(l.y_m, 3) << " | "
       << fixed(l.radius_m, 3) << " | " << l.stops << " | " << l.status << " |\n";
}

}  // namespace

void writeReport(const std::filesystem::path& dir, const ReportInputs& in) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const CalibrationModel& m = *in.model;
  std::ostringstream md;
  md << "# lidarcal calibration report\n\n";
  md << "Sequence `" << in.sequence.string() << "`: " << plural(in.scans, "scan") << " at "
     << plural(in.stops, "stop");
  if (in.known)
    md << ", " << plural(in.known->size(), "reading")
       << " of known true distance (reference measurements).\n\n";
  else
    md << ", " << plural(m.landmarks.size(), "landmark") << " in "
       << plural(in.detections, "detection") << ".\n\n";
  if (!m.status.ok()) {
    md << "**Calibration failed: " << m.status.name() << ".** " << m.status.message << "\n";
    io::writeTextAtomically(dir / "report.md", md.str());
    return;
  }
  std::optional<PlotData> p;
  if (in.observations && in.known)
    p = knownPlotData(*in.known, *in.observations, m);
  else if (in.observations)
    p = plotData(*in.observations, m, in.true_landmarks);
  const FittedRange fitted = p ? p->fitted : FittedRange{};
  writeModelSection(md, m, fitted);
  if (in.correction)
    if (const std::string beyond = beyondFitText(*in.correction, m, in.outside); !beyond.empty()) {
      std::string text = beyond;
      for (std::size_t at = text.find("\nwarning: "); at != std::string::npos;
           at = text.find("\nwarning: ", at))
        text.replace(at, 10, "\n\n**Warning**: ");
      md << "\n" << text << "\n";
    }
  writeErrorTable(md, m, fitted);
  writeTruthSection(md, in);
  writePlotsSection(md, dir, m, p, fitted);
  writeOrderSection(md, m);
  writeNoiseSection(md, m);
  if (!m.landmarks.empty()) writeLandmarksSection(md, m);
  md << "\n## References\n\n" << papers::kReferences;
  if (!in.command.empty()) md << "\nProduced by `" << in.command << "`.\n";
  io::writeTextAtomically(dir / "report.md", md.str());
}

}  // namespace lidarcal::pipeline
