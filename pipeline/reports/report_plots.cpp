// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/reports/report_plots.hpp"

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
#include "common/ray_circle.hpp"
#include "io/atomic_file.hpp"
#include "io/gnuplot.hpp"
#include "io/output_files.hpp"
#include "pipeline/reports/model_text.hpp"
#include "pipeline/reports/papers.hpp"
#include "pipeline/reports/words.hpp"

namespace lidarcal::pipeline {
namespace {

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

}  // namespace

PlotData plotData(const LandmarkObservations& obs, const CalibrationModel& m,
                  const std::vector<Cylinder>& truth) {
  PlotData p;
  ReadingTally tally(m);
  std::ostringstream raw, cor, circles, stops, true_circles;
  for (auto* o : {&raw, &cor, &stops}) o->precision(6);
  const std::map<int, const CalibratedLandmark*> lm = locatedLandmarks(m);
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
      const double d = rayCircleDistance(est.x_m, est.y_m, est.yaw_rad + b.angle_rad,
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

std::pair<double, double> plotRange(const FittedRange& fitted) {
  const double margin = std::max(0.1, 0.1 * (fitted.max_m - fitted.min_m));
  return {std::max(0.0, fitted.min_m - margin), fitted.max_m + margin};
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
    plotted = io::runGnuplot(dir, "plots.gp", &why);
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

}  // namespace lidarcal::pipeline
