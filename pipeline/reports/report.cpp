// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/reports/report.hpp"

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
#include "io/gnuplot.hpp"
#include "io/output_files.hpp"
#include "pipeline/reports/model_text.hpp"
#include "pipeline/reports/papers.hpp"
#include "pipeline/reports/report_plots.hpp"
#include "pipeline/reports/words.hpp"

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

std::string comparisonRow(const ComparedModel& c) {
  const auto& l = c.evaluation.landmarks;
  const auto& a = c.evaluation.all;
  return "| " + c.name + " | " + std::to_string(c.model.model.bias.order()) + " | " +
         fixed(l.mse_ratio, 2) + " | " + fixed(a.mse_ratio, 2) + " | " +
         fixed(1000 * std::sqrt(l.mse_corrected_m2), 2) + " | " + fixed(a.nmse_corrected, 5) +
         " |\n";
}

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

void writeOrderSection(std::ostringstream& md, const CalibrationModel& m) {
  md << "\n## Order selection\n\n| order | alpha | AIC | BIC | validation MSE [mm^2] | test MSE "
        "[mm^2] |\n|---|---|---|---|---|---|\n";
  for (const auto& o : m.orders)
    md << "| " << o.order << " | " << polynomialText(o.alpha) << " | " << fixed(o.aic, 1) << " | "
       << fixed(o.bic, 1) << " | " << fixedOrDash(1e6 * o.validation_mse_m2, 2) << " | "
       << fixedOrDash(1e6 * o.test_mse_m2, 2) << " |\n";
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
  io::makeDirectory(dir);
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
