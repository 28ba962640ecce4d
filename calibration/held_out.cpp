// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/held_out.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "calibration/discrepancy.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {

double curveStandardError(const CalibrationModel& m, double d) {
  const std::size_t n = m.model.bias.alpha.size();
  if (n == 0 || m.alpha_covariance.size() != n * n) return kNaN;
  std::vector<double> x(n);
  double p = 1.0;
  for (std::size_t i = 0; i < n; ++i, p *= d) x[i] = p;
  double v = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) v += x[i] * m.alpha_covariance[i * n + j] * x[j];
  return std::sqrt(std::max(0.0, v));
}

double noiseLawExponent(const NoiseModel& noise) {
  switch (noise.kind) {
    case NoiseKind::squared:
      return 2.0;
    case NoiseKind::power:
      return noise.exponent;
    default:
      return 0.0;
  }
}

bool HeldOutEntry::inside(const Discrepancy& discrepancy, double level) const {
  const double predictive = predictive_se_m * predictive_se_m, own = entry_se_m * entry_se_m;
  const double factor = predictiveFactor(discrepancy, level, knownShare(predictive, own));
  return std::abs(residual_m) <= factor * std::sqrt(predictive + own);
}

namespace {

/// The readings' residuals about the model's f, one per measured entry, weighted by its noise law.
std::vector<EntryResidual> residualsAboutModel(const CalibrationModel& model,
                                               const std::vector<KnownReading>& readings) {
  const BiasPolynomial& f = model.model.bias;
  const double k = noiseLawExponent(model.model.noise);
  std::vector<double> d, y, w, tape;
  std::vector<std::size_t> entry;
  for (const KnownReading& r : readings) {
    d.push_back(r.d_m);
    y.push_back(r.y_m);
    w.push_back(k == 0.0 ? 1.0 : std::pow(std::max(std::abs(f(r.d_m)), 1e-3), -2.0 * k));
    tape.push_back(r.tape_sigma_m);
    entry.push_back(r.entry);
  }
  return entryResiduals(d, y, w, entry, tape, f);
}

}  // namespace

std::vector<HeldOutEntry> heldOutEntries(const CalibrationModel& model,
                                         const std::vector<KnownReading>& readings) {
  std::vector<HeldOutEntry> out;
  for (const EntryResidual& e : residualsAboutModel(model, readings)) {
    HeldOutEntry h;
    h.entry = e.entry;
    h.distance_m = e.distance_m;
    h.residual_m = e.residual_m;
    h.curve_se_m = curveStandardError(model, e.distance_m);
    h.predictive_se_m = predictiveStandardError(h.curve_se_m, model.discrepancy);
    h.entry_se_m = std::sqrt(e.known_variance_m2);
    out.push_back(h);
  }
  return out;
}

Discrepancy discrepancyOfMeasuredEntries(const CalibrationModel& model,
                                         const std::vector<KnownReading>& readings) {
  return estimateDiscrepancy(residualsAboutModel(model, readings), model.model.bias.order());
}

std::vector<std::string> disagreeingEntryWarnings(const CalibrationModel& model,
                                                  const std::vector<KnownReading>& readings,
                                                  double alpha) {
  std::map<std::size_t, std::size_t> stop_of;
  for (const KnownReading& r : readings) stop_of[r.entry] = r.stop;
  const std::vector<DeletedResidual> deleted =
      deletedResiduals(residualsAboutModel(model, readings), model.model.bias.order());
  std::vector<std::string> out;
  const double n = static_cast<double>(deleted.size());
  for (const DeletedResidual& e : deleted) {
    const double p = std::min(1.0, n * e.p_value);
    if (!(p < alpha)) continue;
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "distances[%zu] (stop %zu, its beams at %.3f m) disagrees with the other "
                  "measured distances: its readings lie "
                  "%+.1f mm from what the others predict, %.1f standard errors (p = %.1g over %zu "
                  "entries, Bonferroni); "
                  "check its stop number, tape reading and target. Left in, it widens the model "
                  "discrepancy and every "
                  "predictive interval",
                  e.entry, stop_of[e.entry], e.distance_m, 1000.0 * e.error_m,
                  std::abs(e.error_m / e.se_m), p, deleted.size());
    out.push_back(buf);
  }
  return out;
}

HalfCheck checkInterleavedHalf(const std::vector<KnownReading>& readings, int fit_parity,
                               const CalibrationConfig& config) {
  std::vector<KnownReading> fitted, held;
  for (const KnownReading& r : readings)
    (static_cast<int>(r.stop % 2) == fit_parity ? fitted : held).push_back(r);
  HalfCheck out;
  out.model = calibrateWithReference(fitted, config);
  if (out.model.status.ok()) out.held_out = heldOutEntries(out.model, held);
  return out;
}

}  // namespace lidarcal::calibration
