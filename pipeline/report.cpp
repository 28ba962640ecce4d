#include "pipeline/report.hpp"

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "calibration/inversion.hpp"
#include "calibration/joint_refinement.hpp"
#include "io/atomic_file.hpp"
#include "pipeline/gnuplot.hpp"

namespace lidarcal::pipeline {
namespace {

/// v with `digits` decimals (and a sign when `sign`).
std::string num(double v, int digits, bool sign = false) {
  char buf[64];
  if (sign) std::snprintf(buf, sizeof buf, "%+.*f", digits, v);
  else std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

std::string polynomialText(const std::vector<double>& a) {
  std::string s;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (i) s += a[i] < 0 ? " - " : " + ";
    else if (a[i] < 0) s += "-";
    s += num(std::abs(a[i]), 5);
    if (i == 1) s += " d";
    if (i > 1) s += " d^" + std::to_string(i);
  }
  return s;
}

std::string noiseText(const NoiseModel& n, const BiasPolynomial& f) {
  switch (n.kind) {
    case NoiseKind::squared:
      return "sigma(d) = " + num(n.sigma_e, 5) + " f(d)^2 (seed 004 eq. 1): " + num(1000 * n.stddev(1.0, f), 1) +
             " mm at 1 m, " + num(1000 * n.stddev(3.0, f), 1) + " mm at 3 m";
    case NoiseKind::polynomial: return "sigma(d) = |" + polynomialText(n.beta) + "| (seed 000 eq. 3)";
    case NoiseKind::constant: return "sigma = " + num(n.sigma_e, 4) + " m";
    default: return toString(n.kind);
  }
}

struct PlotData {
  std::string distance, curve, noise, raw, corrected, circles, stops;
};

PlotData plotData(const LandmarkObservations& obs, const CalibrationModel& m) {
  PlotData p;
  std::ostringstream dist, raw, cor, noise, curve, circles, stops;
  dist.precision(6);
  raw.precision(6);
  cor.precision(6);
  std::map<int, const CalibratedLandmark*> lm;
  for (const auto& l : m.landmarks)
    if (l.status == "ok") lm[l.id] = &l;
  std::optional<calibration::RangeInverter> inv;
  try {
    inv.emplace(m.model, calibration::inversionWindow(m.model, calibration::InversionMethod::ls));
  } catch (const std::invalid_argument&) {
  }
  std::map<int, std::pair<double, int>> bins;  // 0.25 m bins of the estimated distance
  std::map<int, double> bin_sum2;
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
      const double d = calibration::rayCircleDistance(est.x_m, est.y_m, est.yaw_rad + b.angle_rad, it->second->x_m,
                                                      it->second->y_m, it->second->radius_m);
      dist << d << ' ' << b.range_m << '\n';
      const double r = b.range_m - m.model.bias(d);
      const int bin = static_cast<int>(std::floor(d / 0.25));
      bins[bin].first += d;
      bins[bin].second += 1;
      bin_sum2[bin] += r * r;
      if (!map_scan) continue;
      const double ar = cmd.yaw_rad + b.angle_rad;
      raw << cmd.x_m + b.range_m * std::cos(ar) << ' ' << cmd.y_m + b.range_m * std::sin(ar) << '\n';
      if (inv) {
        if (const auto c = inv->invert(b.range_m)) {
          const double ac = est.yaw_rad + b.angle_rad;
          cor << est.x_m + *c * std::cos(ac) << ' ' << est.y_m + *c * std::sin(ac) << '\n';
        }
      }
    }
  }
  for (const auto& [bin, v] : bins)
    if (v.second >= 5)
      noise << v.first / v.second << ' ' << std::sqrt(bin_sum2[bin] / v.second) << ' '
            << m.model.noise.stddev(v.first / v.second, m.model.bias) << '\n';
  for (double d = 0.0; d <= m.model.range_max_m + 1e-9; d += 0.05) curve << d << ' ' << m.model.bias(d) << ' ' << d << '\n';
  for (const auto& [id, l] : lm) {
    for (int i = 0; i <= 72; ++i) {
      const double a = 2.0 * kPi * i / 72.0;
      circles << l->x_m + l->radius_m * std::cos(a) << ' ' << l->y_m + l->radius_m * std::sin(a) << '\n';
    }
    circles << "\n";
  }
  for (const auto& s : m.stop_poses) stops << s.x_m << ' ' << s.y_m << '\n';
  p.distance = dist.str();
  p.curve = curve.str();
  p.noise = noise.str();
  p.raw = raw.str();
  p.corrected = cor.str();
  p.circles = circles.str();
  p.stops = stops.str();
  return p;
}

constexpr const char* kScript = R"GP(set terminal pngcairo size 900,650 font "DejaVu Sans,11"
set grid
set key top left
set output "distance.png"
set title "Range error of the raw readings against the distance estimated from the landmarks"
set xlabel "estimated true distance d [m]"
set ylabel "raw reading - d [m]"
plot "distance.dat" using 1:($2-$1) with points pt 7 ps 0.3 lc rgb "#8899bb" title "readings on landmarks", \
     "curve.dat" using 1:($2-$1) with lines lw 2 lc rgb "#cc3311" title "fitted bias f(d) - d", \
     0 with lines dt 2 lc rgb "black" title "ideal (no error)"
set output "noise.png"
set title "Noise against distance"
set xlabel "estimated true distance d [m]"
set ylabel "standard deviation of the reading [mm]"
plot "noise.dat" using 1:($2*1000) with points pt 7 ps 1 lc rgb "#0077bb" title "measured (RMS residual, 0.25 m bins)", \
     "noise.dat" using 1:($3*1000) with lines lw 2 lc rgb "#cc3311" title "noise model"
set output "map.png"
set title "Landmarks with raw (red) and corrected (green) points, one scan per stop"
set xlabel "x [m]"
set ylabel "y [m]"
set size ratio -1
set key outside bottom center horizontal
plot "circles.dat" using 1:2 with lines lw 2 lc rgb "#999999" title "landmarks (estimated)", \
     "raw.dat" using 1:2 with points pt 2 ps 0.6 lc rgb "#cc3311" title "raw", \
     "corrected.dat" using 1:2 with points pt 6 ps 0.6 lc rgb "#009944" title "corrected", \
     "stops.dat" using 1:2 with points pt 7 ps 0.8 lc rgb "#0044aa" title "stops"
)GP";

std::string comparisonRow(const ComparedModel& c) {
  const auto& l = c.evaluation.landmarks;
  const auto& a = c.evaluation.all;
  return "| " + c.name + " | " + std::to_string(c.model.model.bias.order()) + " | " + num(l.mse_ratio, 2) + " | " +
         num(a.mse_ratio, 2) + " | " + num(1000 * std::sqrt(l.mse_corrected_m2), 2) + " | " +
         num(a.nmse_corrected, 5) + " |\n";
}

}  // namespace

void writeReport(const std::filesystem::path& dir, const ReportInputs& in) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const CalibrationModel& m = *in.model;
  std::ostringstream md;
  md << "# lidarcal calibration report\n\n";
  md << "Sequence `" << in.sequence.string() << "`: " << in.scans << " scans at " << in.stops << " stops, "
     << m.landmarks.size() << " landmarks in " << in.detections << " detections.\n\n";
  if (m.status != "ok") {
    md << "**Calibration failed: " << m.status << ".** " << m.message << "\n";
    io::writeTextAtomically(dir / "report.md", md.str());
    return;
  }
  md << "## The calibrated model\n\n";
  md << "- method: **" << m.method << "**, bias order n = " << m.model.bias.order() << " (chosen by " << m.order_rule
     << ")\n";
  md << "- bias: reading = f(d) = " << polynomialText(m.model.bias.alpha) << "  (d = true distance in metres)\n";
  md << "- noise: " << noiseText(m.model.noise, m.model.bias) << "\n";
  md << "- bearing noise sigma_theta = " << num(rad2deg(m.sigma_theta_rad), 3) << " deg";
  if (m.method == "joint")
    md << "; stop poses moved by " << num(1000 * m.pose_scatter_m, 1) << " mm and "
       << num(rad2deg(m.heading_scatter_rad), 2) << " deg (RMS) from the commanded ones";
  md << "\n";
  if (!m.message.empty()) md << "- note: " << m.message << "\n";
  md << "\nWhat the raw sensor reads at a few true distances, and the error it makes:\n\n";
  md << "| true distance | raw reading | error | noise (1 sigma) |\n|---|---|---|---|\n";
  for (double d : {0.5, 1.0, 2.0, 3.0, 4.0, 5.0}) {
    if (d > m.model.range_max_m) break;
    md << "| " << num(d, 1) << " m | " << num(m.model.bias(d), 3) << " m | "
       << num(1000 * (m.model.bias(d) - d), 1, true) << " mm | " << num(1000 * m.model.noise.stddev(d, m.model.bias), 1)
       << " mm |\n";
  }
  md << "\n`lidarcal correct` inverts f for every point (seed 004 eq. 30) and moves it along its beam.\n";

  if (!in.compared.empty()) {
    md << "\n## Against the truth\n\n" << in.truth_note << "\n\n";
    md << "| model | order | MSE ratio, landmarks (eq. 31) | MSE ratio, all returns | RMS error after, landmarks [mm] | "
          "normalised MSE after (seed 004 eq. 31) |\n|---|---|---|---|---|---|\n";
    const auto& first = in.compared.front().evaluation;
    md << "| raw readings | - | 1.00 | 1.00 | " << num(1000 * std::sqrt(first.landmarks.mse_raw_m2), 2) << " | "
       << num(first.all.nmse_raw, 5) << " |\n";
    for (const auto& c : in.compared) md << comparisonRow(c);
  }

  const bool plots = in.observations != nullptr;
  std::string why;
  bool plotted = false;
  if (plots) {
    const PlotData p = plotData(*in.observations, m);
    io::writeTextAtomically(dir / "distance.dat", p.distance);
    io::writeTextAtomically(dir / "curve.dat", p.curve);
    io::writeTextAtomically(dir / "noise.dat", p.noise);
    io::writeTextAtomically(dir / "raw.dat", p.raw);
    io::writeTextAtomically(dir / "corrected.dat", p.corrected);
    io::writeTextAtomically(dir / "circles.dat", p.circles);
    io::writeTextAtomically(dir / "stops.dat", p.stops);
    io::writeTextAtomically(dir / "plots.gp", kScript);
    plotted = runGnuplot(dir, "plots.gp", &why);
  }
  md << "\n## Plots\n\n";
  if (plotted) {
    md << "![readings against estimated distance](distance.png)\n\n";
    md << "![noise against distance](noise.png)\n\n";
    md << "![landmark map, raw and corrected points](map.png)\n";
  } else {
    md << "(" << (plots ? why : std::string("no plot data")) << ")\n";
  }

  md << "\n## Order selection\n\n| order | alpha | AIC | BIC | validation MSE [mm^2] | test MSE [mm^2] |\n|---|---|---|---|---|---|\n";
  for (const auto& o : m.orders)
    md << "| " << o.order << " | " << polynomialText(o.alpha) << " | " << num(o.aic, 1) << " | " << num(o.bic, 1)
       << " | " << (std::isfinite(o.validation_mse_m2) ? num(1e6 * o.validation_mse_m2, 2) : "-") << " | "
       << (std::isfinite(o.test_mse_m2) ? num(1e6 * o.test_mse_m2, 2) : "-") << " |\n";
  md << "\nAIC picks order " << m.order_aic;
  if (m.order_validation >= 0) md << ", held-out validation order " << m.order_validation;
  md << ".\n";

  const auto& nf = m.noise_fits;
  md << "\n## Noise estimators side by side\n\n";
  md << "| estimator | result |\n|---|---|\n";
  md << "| seed 000 polynomial noise, ML | sigma(d) = |" << polynomialText(nf.seed000_beta) << "| |\n";
  md << "| seed 004 closed form (eqs. 21-26) | f = " << polynomialText(nf.seed004_cf_alpha) << ", sigma_e = "
     << num(nf.seed004_cf_sigma_e, 5) << " |\n";
  md << "| seed 004 full ML (eqs. 18-20) | f = " << polynomialText(nf.seed004_ml_alpha) << ", sigma_e = "
     << num(nf.seed004_ml_sigma_e, 5) << " |\n";
  for (const auto& [name, reason] : nf.unavailable) md << "| " << name << " | not available: " << reason << " |\n";
  if (nf.exponent_best >= 0) {
    md << "\nSeed 004's noise-exponent test (eqs. 10-15) on " << nf.exponent_batches
       << " constant-distance batches (one beam over the scans of a stop): log-likelihood of y = f + f^k e for k = 0..3: ";
    for (int k = 0; k < 4; ++k) md << (k ? ", " : "") << num(nf.exponent_loglik[static_cast<std::size_t>(k)], 1);
    md << "; best k = **" << nf.exponent_best << "**.\n";
  }
  md << "\n## Landmarks\n\n| id | x [m] | y [m] | radius [m] | stops | status |\n|---|---|---|---|---|---|\n";
  for (const auto& l : m.landmarks)
    md << "| " << l.id << " | " << num(l.x_m, 3) << " | " << num(l.y_m, 3) << " | " << num(l.radius_m, 3)
       << " | " << l.stops << " | " << l.status << " |\n";
  if (!in.command.empty()) md << "\nProduced by `" << in.command << "`.\n";
  io::writeTextAtomically(dir / "report.md", md.str());
}

}  // namespace lidarcal::pipeline
