// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/reference.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <Eigen/Dense>

#include "calibration/calibrate.hpp"
#include "calibration/discrepancy.hpp"
#include "calibration/held_out.hpp"
#include "calibration/inversion.hpp"
#include "calibration/jackknife.hpp"
#include "calibration/joint_refinement.hpp"
#include "calibration/noise_exponent.hpp"
#include "calibration/range_model_fit.hpp"
#include "common/information_criteria.hpp"
#include "common/number_text.hpp"
#include "common/plural.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {
namespace {

/// v with `digits` decimals.
/// Running mean and spread of a quantity over the scans of a stop, with a circular mean of an
/// angle.
struct Tally {
  std::size_t n = 0;
  double sum = 0.0, sum2 = 0.0, sin = 0.0, cos = 0.0;
  std::vector<double> radii;
  void add(double value, double angle_rad) {
    ++n;
    sum += value;
    sum2 += value * value;
    sin += std::sin(angle_rad);
    cos += std::cos(angle_rad);
  }
  double mean() const { return sum / static_cast<double>(n); }
  double standardError() const {
    if (n < 2) return kNaN;
    const double var =
        std::max(0.0, (sum2 - sum * sum / static_cast<double>(n)) / static_cast<double>(n - 1));
    return std::sqrt(var / static_cast<double>(n));
  }
  double angle() const { return std::atan2(sin, cos); }
};

/// The key of `tallies` that matches the entry: among the targets within the bearing tolerance
/// (all of them without a bearing), the one whose measured distance is nearest distance_m, if
/// that is within the distance tolerance; `why` says what was found instead. (Two poles on one
/// bearing: the distance tells them apart.)
template <class Key>
std::optional<Key> choose(const std::map<Key, Tally>& tallies, const ReferenceDistance& e,
                          const ReferenceConfig& c, std::string& why) {
  std::optional<Key> best;
  double best_error = std::numeric_limits<double>::infinity(), nearest_bearing = best_error;
  for (const auto& [key, t] : tallies) {
    if (e.bearing_rad) {
      const double off = std::abs(wrapAngle(t.angle() - *e.bearing_rad));
      nearest_bearing = std::min(nearest_bearing, off);
      if (off > c.max_bearing_error_rad) continue;
    }
    const double error = std::abs(t.mean() - e.distance_m);
    if (error < best_error) {
      best_error = error;
      best = key;
    }
  }
  if (!best) {
    why = "the nearest is " + fixed(nearest_bearing, 3) + " rad from bearing_rad (more than " +
          fixed(c.max_bearing_error_rad, 2) + " rad)";
    return best;
  }
  if (best_error <= 0.1 + c.max_distance_error_fraction * e.distance_m) return best;
  why = std::string(e.bearing_rad ? "the nearest in distance at that bearing" : "the nearest") +
        " measures " + fixed(tallies.at(*best).mean(), 3) + " m, too far from distance_m";
  return std::nullopt;
}

void landmarkReadings(const LandmarkObservations& obs, const ReferenceDistance& e, double radius_m,
                      const ReferenceConfig& c, ReferenceMatch& m, std::vector<KnownReading>& out) {
  std::map<int, Tally> tallies;
  for (const auto& s : obs.sightings) {
    if (s.stop != e.stop) continue;
    Tally& t = tallies[s.landmark];
    t.add(s.centre_range_m, s.bearing_rad);
    t.radii.push_back(s.radius_m);
  }
  if (tallies.empty()) {
    m.status = "no pole was detected at stop " + std::to_string(e.stop) +
               " (check it with lidarcal detect; give the pole radius with --radius)";
    return;
  }
  std::string why;
  const auto id = choose(tallies, e, c, why);
  if (!id) {
    m.status = "no pole at stop " + std::to_string(e.stop) + " matches this entry: " + why;
    return;
  }
  const Tally& t = tallies.at(*id);
  m.landmark = *id;
  m.sightings = t.n;
  m.measured_m = t.mean();
  m.measured_se_m = t.standardError();
  m.bearing_rad = t.angle();
  const double r = radius_m > 0.0 ? radius_m : median(t.radii);
  m.surface_m = e.distance_m - r;
  // The measured centre, on the detected bearing (a pole's arc is symmetric about it, whatever
  // the range bias): every beam's true distance follows from it.
  const double cx = e.distance_m * std::cos(m.bearing_rad),
               cy = e.distance_m * std::sin(m.bearing_rad);
  for (const auto& s : obs.sightings) {
    if (s.stop != e.stop || s.landmark != *id) continue;
    for (const auto& b : s.beams) {
      if (!std::isfinite(b.range_m)) continue;
      const double perp = cy * std::cos(b.angle_rad) - cx * std::sin(b.angle_rad);
      if (std::abs(perp) > c.lateral_fraction * r) continue;
      const double d = rayCircleDistance(0.0, 0.0, b.angle_rad, cx, cy, r);
      if (!(d > 0.0)) continue;
      out.push_back({m.entry, s.stop, s.scan, b.beam, d, b.range_m, b.angle_rad, e.sigma_m});
      ++m.readings;
    }
  }
  if (m.readings == 0)
    m.status =
        "the pole matched at stop " + std::to_string(e.stop) + " has no beam near its centre";
}

void wallReadings(const LandmarkObservations& obs, const ReferenceDistance& e,
                  const ReferenceConfig& c, ReferenceMatch& m, std::vector<KnownReading>& out) {
  // Per scan, the wall that matches the entry best; then over the stop.
  // scan -> wall index -> tally of one
  std::map<std::size_t, std::map<std::size_t, Tally>> by_scan;
  for (std::size_t w = 0; w < obs.walls.size(); ++w) {
    const WallSighting& ws = obs.walls[w];
    if (ws.stop != e.stop) continue;
    by_scan[ws.scan][w].add(ws.distance_m, ws.normal_rad);
  }
  if (by_scan.empty()) {
    m.status = "no wall was found at stop " + std::to_string(e.stop);
    return;
  }
  Tally stop_tally;
  std::vector<std::size_t> chosen;
  std::string why;
  for (const auto& [scan, walls] : by_scan) {
    const auto w = choose(walls, e, c, why);
    if (!w) continue;
    chosen.push_back(*w);
    stop_tally.add(obs.walls[*w].distance_m, obs.walls[*w].normal_rad);
  }
  if (chosen.empty()) {
    m.status = "no wall at stop " + std::to_string(e.stop) + " matches this entry: " + why;
    return;
  }
  m.sightings = stop_tally.n;
  m.measured_m = stop_tally.mean();
  m.measured_se_m = stop_tally.standardError();
  m.bearing_rad = stop_tally.angle();
  for (std::size_t w : chosen) {
    const WallSighting& ws = obs.walls[w];
    for (const auto& b : ws.beams) {
      const double incidence = wrapAngle(b.angle_rad - m.bearing_rad);
      if (!std::isfinite(b.range_m) || std::abs(incidence) > c.max_wall_incidence_rad) continue;
      out.push_back({m.entry, ws.stop, ws.scan, b.beam, e.distance_m / std::cos(incidence),
                     b.range_m, b.angle_rad, e.sigma_m});
      ++m.readings;
    }
  }
  if (m.readings == 0)
    m.status = "the wall matched at stop " + std::to_string(e.stop) +
               " has no beam within the incidence limit";
}

Eigen::VectorXd powers(double d, int order) {
  Eigen::VectorXd x(order + 1);
  double p = 1.0;
  for (int i = 0; i <= order; ++i, p *= d) x(i) = p;
  return x;
}

double polyAt(const std::vector<double>& a, double d) {
  double f = 0.0;
  for (std::size_t i = a.size(); i-- > 0;) f = f * d + a[i];
  return f;
}

/// Weights of the noise law at the current f: 1 / f(d)^(2k) (f floored at 1 mm).
std::vector<double> lawWeights(const std::vector<double>& alpha, const std::vector<double>& d,
                               double exponent, const std::vector<bool>& use) {
  std::vector<double> w(d.size(), 0.0);
  for (std::size_t i = 0; i < d.size(); ++i)
    if (use[i])
      w[i] = exponent == 0.0
                 ? 1.0
                 : std::pow(std::max(std::abs(polyAt(alpha, d[i])), 1e-3), -2.0 * exponent);
  return w;
}

/// Iterated weighted least squares on the readings with use[i], the noise law's weights times
/// factor[i] (none when empty).
std::vector<double> iteratedFit(const std::vector<double>& d, const std::vector<double>& y,
                                const std::vector<bool>& use, int order, double exponent,
                                const std::vector<double>& factor) {
  std::vector<double> dd, yy, ww;
  std::vector<double> alpha(static_cast<std::size_t>(order) + 1, 0.0);
  alpha[1] = 1.0;  // f(d) = d to start the weights
  for (int it = 0; it < (exponent == 0.0 ? 1 : 20); ++it) {
    const std::vector<double> w = lawWeights(alpha, d, exponent, use);
    dd.clear(), yy.clear(), ww.clear();
    for (std::size_t i = 0; i < d.size(); ++i)
      if (use[i])
        dd.push_back(d[i]), yy.push_back(y[i]),
            ww.push_back(factor.empty() ? w[i] : w[i] * factor[i]);
    std::vector<double> next = fitPolynomial(dd, yy, order, ww);
    double change = 0.0;
    for (std::size_t i = 0; i < next.size(); ++i)
      change = std::max(change, std::abs(next[i] - alpha[i]));
    alpha = std::move(next);
    if (change < 1e-12) break;
  }
  return alpha;
}

}  // namespace

void ReferenceConfig::validate() const {
  if (!(lateral_fraction > 0.0 && lateral_fraction <= 1.0))
    throw std::invalid_argument("ReferenceConfig: lateral_fraction must be in (0, 1]");
  if (!(max_wall_incidence_rad > 0.0 && max_wall_incidence_rad < 1.5))
    throw std::invalid_argument("ReferenceConfig: max_wall_incidence_rad must be in (0, 1.5)");
  if (!(max_bearing_error_rad > 0.0))
    throw std::invalid_argument("ReferenceConfig: max_bearing_error_rad must be positive");
  if (!(max_distance_error_fraction > 0.0))
    throw std::invalid_argument("ReferenceConfig: max_distance_error_fraction must be positive");
}

ReferenceReadings knownReadings(const LandmarkObservations& obs, const Reference& ref,
                                double radius_m, const ReferenceConfig& config) {
  config.validate();
  ReferenceReadings out;
  for (std::size_t k = 0; k < ref.distances.size(); ++k) {
    const ReferenceDistance& e = ref.distances[k];
    ReferenceMatch m;
    m.entry = k;
    m.stop = e.stop;
    m.target = e.target;
    m.reference_m = e.distance_m;
    m.surface_m = e.distance_m;
    if (e.target == ReferenceTarget::landmark)
      landmarkReadings(obs, e, radius_m, config, m, out.readings);
    else
      wallReadings(obs, e, config, m, out.readings);
    out.matches.push_back(m);
  }
  return out;
}

ClusteredFit fitClustered(const std::vector<double>& d, const std::vector<double>& y,
                          const std::vector<std::size_t>& cluster, int order, double exponent,
                          const std::vector<double>& factor) {
  if (d.size() != y.size() || d.size() != cluster.size() ||
      (!factor.empty() && factor.size() != d.size()))
    throw std::invalid_argument("fitClustered: sizes differ");
  const std::vector<bool> all(d.size(), true);
  ClusteredFit fit;
  fit.alpha = iteratedFit(d, y, all, order, exponent, factor);
  const std::vector<double> law = lawWeights(fit.alpha, d, exponent, all);
  std::vector<double> w = law;  // the fit's weights
  if (!factor.empty())
    for (std::size_t i = 0; i < d.size(); ++i) w[i] *= factor[i];
  const int p = order + 1;
  Eigen::MatrixXd bread = Eigen::MatrixXd::Zero(p, p);
  std::map<std::size_t, Eigen::VectorXd> score;  // per cluster: sum of w r x
  double s2 = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const Eigen::VectorXd x = powers(d[i], order);
    const double r = y[i] - polyAt(fit.alpha, d[i]);
    bread += w[i] * x * x.transpose();
    auto it = score.find(cluster[i]);
    if (it == score.end()) it = score.emplace(cluster[i], Eigen::VectorXd::Zero(p)).first;
    it->second += w[i] * r * x;
    s2 += law[i] * r * r;
  }
  const double n = static_cast<double>(d.size());
  fit.sigma_e = std::sqrt(s2 / n);
  Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(p, p);
  for (const auto& [g, sc] : score) meat += sc * sc.transpose();
  const double groups = static_cast<double>(score.size());
  const Eigen::MatrixXd inv = bread.ldlt().solve(Eigen::MatrixXd::Identity(p, p));
  fit.covariance = inv * meat * inv * (groups > 1.0 ? groups / (groups - 1.0) : 1.0);
  // Gaussian NLL of y ~ N(f(d), sigma_e^2 f(d)^(2k)).
  fit.neg_log_likelihood = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double sigma = fit.sigma_e / std::sqrt(law[i]);
    const double r = y[i] - polyAt(fit.alpha, d[i]);
    fit.neg_log_likelihood += 0.5 * (kLog2Pi + 2.0 * std::log(sigma) + r * r / (sigma * sigma));
  }
  // Leave one cluster out: fit on the others, the weighted squared error on it; the spread of
  // those fits is the jackknife covariance (which, unlike the sandwich above, does not shrink
  // with few clusters: with 10 stops the sandwich's 95 % intervals held the truth in 83-92 % of
  // simulated cases; docs/results/standard-errors.md).
  double cv = 0.0, cv_w = 0.0;
  std::vector<Eigen::VectorXd> leave_out;
  for (const auto& [g, sc] : score) {
    std::vector<bool> use(d.size());
    for (std::size_t i = 0; i < d.size(); ++i) use[i] = cluster[i] != g;
    const std::vector<double> a = iteratedFit(d, y, use, order, exponent, factor);
    leave_out.push_back(Eigen::Map<const Eigen::VectorXd>(a.data(), p));
    for (std::size_t i = 0; i < d.size(); ++i)
      if (!use[i]) {
        const double r = y[i] - polyAt(a, d[i]);
        cv += w[i] * r * r;
        cv_w += w[i];
      }
  }
  fit.cv_mse_m2 = cv_w > 0.0 ? cv / cv_w : kNaN;
  if (leave_out.size() >= 2) fit.covariance = jackknifeCovariance(leave_out);
  return fit;
}

std::vector<KnownRange> knownRanges(const ReferenceReadings& known, const Reference& ref) {
  // Per entry, the readings of each beam pooled (beam angles to 1e-5 rad, as the joint
  // refinement pools repeated scans).
  std::map<std::size_t, std::map<long long, KnownRange::Beam>> beams;
  for (const KnownReading& r : known.readings) {
    KnownRange::Beam& b = beams[r.entry][std::llround(r.angle_rad * 1e5)];
    b.angle_rad = r.angle_rad;
    b.distance_m += r.d_m;
    b.mean_reading_m += r.y_m;
    b.count += 1.0;
  }
  std::vector<KnownRange> out;
  for (const auto& m : known.matches) {
    const auto it = beams.find(m.entry);
    if (!m.ok() || it == beams.end() || m.entry >= ref.distances.size()) continue;
    KnownRange k;
    k.pole = m.target == ReferenceTarget::landmark;
    k.centre_x_m = m.reference_m * std::cos(m.bearing_rad);  // as landmarkReadings places it
    k.centre_y_m = m.reference_m * std::sin(m.bearing_rad);
    k.tape_sigma_m = ref.distances[m.entry].sigma_m;
    for (auto& [key, b] : it->second) {
      b.distance_m /= b.count;
      b.mean_reading_m /= b.count;
      k.beams.push_back(b);
    }
    out.push_back(std::move(k));
  }
  return out;
}

double testReadingNoise(const std::vector<KnownReading>& readings, const CalibrationConfig& config,
                        NoiseFits& fits) {
  // One batch: one beam on one target at one stop (a constant true distance), in scan order.
  std::map<std::tuple<std::size_t, std::size_t, std::uint32_t>,
           std::vector<std::pair<std::size_t, double>>>
      by_beam;
  for (const auto& r : readings)
    if (r.beam != kUnknownBeam) by_beam[{r.stop, r.entry, r.beam}].push_back({r.scan, r.y_m});
  std::vector<std::vector<double>> batches;
  for (auto& [key, v] : by_beam) {
    std::sort(v.begin(), v.end());
    std::vector<double> b;
    for (const auto& [scan, value] : v) b.push_back(value);
    batches.push_back(std::move(b));
  }
  const NoiseExponentTest test = testNoiseExponent(batches);
  fits.exponent_loglik = test.log_likelihood;
  fits.exponent_best = test.best;
  fits.exponent_batches = test.batches;
  if (test.best < 0) fits.unavailable["exponent_test"] = "no beam was read repeatedly at one stop";
  return test.best >= 0 ? test.best : (config.noise == NoiseKind::constant ? 0.0 : 2.0);
}

void setNoiseLaw(NoiseModel& noise, double exponent, double sigma_e) {
  noise.kind = exponent == 0.0   ? NoiseKind::constant
               : exponent == 2.0 ? NoiseKind::squared
                                 : NoiseKind::power;
  noise.sigma_e = sigma_e;
  noise.exponent = exponent;
}

namespace {

/// The known-distance readings as columns, with the number of stops they come from.
struct ReadingColumns {
  std::vector<double> d, y, tape_sigma;
  std::vector<std::size_t> stop, entry;
  std::size_t stops = 0;
};

ReadingColumns columnsOf(const std::vector<KnownReading>& readings) {
  ReadingColumns c;
  std::set<std::size_t> stops;
  for (const auto& r : readings) {
    c.d.push_back(r.d_m);
    c.y.push_back(r.y_m);
    c.tape_sigma.push_back(r.tape_sigma_m);
    c.stop.push_back(r.stop);
    c.entry.push_back(r.entry);
    stops.insert(r.stop);
  }
  c.stops = stops.size();
  return c;
}

/// Fits every order the stops can support (leave-one-out needs more stops than coefficients)
/// into `fits` and m.orders; returns the index of the invertible order with the smallest
/// leave-one-stop-out error, -1 when none is invertible over the distances measured.
int fitEveryOrder(const ReadingColumns& c, double exponent, const CalibrationConfig& config,
                  CalibrationModel& m, std::vector<ClusteredFit>& fits) {
  const double d_lo = *std::min_element(c.d.begin(), c.d.end()),
               d_hi = *std::max_element(c.d.begin(), c.d.end());
  int best = -1;
  for (int n = 1; n <= config.max_order && static_cast<std::size_t>(n) + 2 <= c.stops; ++n) {
    fits.push_back(fitClustered(c.d, c.y, c.stop, n, exponent));
    const ClusteredFit& f = fits.back();
    OrderRow row;
    row.order = n;
    row.alpha = f.alpha;
    const double k = n + 2.0;
    row.aic = akaike(k, f.neg_log_likelihood);
    row.bic = schwarz(k, c.d.size(), f.neg_log_likelihood);
    row.validation_mse_m2 = f.cv_mse_m2;
    row.test_mse_m2 = kNaN;
    row.invertible = isMonotone(BiasPolynomial{f.alpha}, d_lo, d_hi);
    m.orders.push_back(row);
    if (row.invertible &&
        (best < 0 || f.cv_mse_m2 < fits[static_cast<std::size_t>(best)].cv_mse_m2))
      best = n - 1;
  }
  return best;
}

/// The invertible order of smallest AIC in m.orders, -1 when none.
int orderByAic(const CalibrationModel& m) {
  int order = -1;
  for (const auto& row : m.orders)
    if (row.invertible &&
        (order < 0 || row.aic < m.orders[static_cast<std::size_t>(order - 1)].aic))
      order = row.order;
  return order;
}

/// m's bias, noise law, covariance, fitted range and residual RMS from the fit it adopts.
void adoptFit(CalibrationModel& m, const ClusteredFit& f, const ReadingColumns& c,
              double exponent) {
  m.model.bias.alpha = f.alpha;
  setNoiseLaw(m.model.noise, exponent, f.sigma_e);
  m.alpha_covariance.assign(f.covariance.data(), f.covariance.data() + f.covariance.size());
  m.fitted_range_m = fittedRange(c.d, c.y, m.model.bias);
  m.readings = c.d.size();
  double s = 0.0;
  for (std::size_t i = 0; i < c.d.size(); ++i) s += std::pow(c.y[i] - polyAt(f.alpha, c.d[i]), 2);
  m.residual_rms_m = std::sqrt(s / static_cast<double>(c.d.size()));
}

/// The model discrepancy over the entries about the chosen fit f (calibration/discrepancy.hpp),
/// and the fit to adopt at f's order: f refitted with the random-effects weights, or f itself
/// where those are the noise law's.
std::pair<ClusteredFit, Discrepancy> randomEffectsFit(const ClusteredFit& f,
                                                      const ReadingColumns& c, double exponent) {
  const int order = static_cast<int>(f.alpha.size()) - 1;
  const std::vector<double> w =
      lawWeights(f.alpha, c.d, exponent, std::vector<bool>(c.d.size(), true));
  const std::vector<EntryResidual> entries =
      entryResiduals(c.d, c.y, w, c.entry, c.tape_sigma, BiasPolynomial{f.alpha});
  Discrepancy discrepancy = estimateDiscrepancy(entries, order);
  const auto factors = randomEffectsFactors(entries, discrepancy);
  if (factors.empty()) return {f, std::move(discrepancy)};
  std::vector<double> factor(c.d.size(), 0.0);
  for (std::size_t i = 0; i < c.d.size(); ++i)
    if (const auto it = factors.find(c.entry[i]); it != factors.end()) factor[i] = it->second;
  return {fitClustered(c.d, c.y, c.stop, order, exponent, factor), std::move(discrepancy)};
}

}  // namespace

CalibrationModel calibrateWithReference(const std::vector<KnownReading>& readings,
                                        const CalibrationConfig& config, double range_min_m,
                                        double range_max_m) {
  config.validate();
  CalibrationModel m;
  m.method = "reference";
  m.model.range_min_m = range_min_m;
  m.model.range_max_m = range_max_m;
  const ReadingColumns c = columnsOf(readings);
  if (c.stops < 3) {
    m.status.code = StatusCode::too_few_reference_stops;
    m.status.message = "known distances at " + plural(c.stops, "stop") +
                       ": a range model needs measured distances at 3 or more stops (better 10 or "
                       "more, spread over "
                       "the range you will use the sensor at), or wall-to-wall spans beside them "
                       "(docs/FORMAT.md#wall-to-wall-spans)";
    return m;
  }
  const double exponent = testReadingNoise(readings, config, m.noise_fits);
  const double d_lo = *std::min_element(c.d.begin(), c.d.end()),
               d_hi = *std::max_element(c.d.begin(), c.d.end());
  std::vector<ClusteredFit> fits;
  const int best = fitEveryOrder(c, exponent, config, m, fits);
  if (best < 0) {
    m.status.code = StatusCode::no_invertible_order;
    m.status.message = "no polynomial order fitted to the known distances increases over " +
                       fixed(d_lo, 3) + "-" + fixed(d_hi, 3) +
                       " m: measure more distances across that range";
    return m;
  }
  m.order_rule = "leave-one-stop-out cross-validation";
  m.order_aic = orderByAic(m);
  m.order_validation = best + 1;
  auto [fit, discrepancy] = randomEffectsFit(fits[static_cast<std::size_t>(best)], c, exponent);
  adoptFit(m, fit, c, exponent);
  m.discrepancy = std::move(discrepancy);
  for (std::string& w : disagreeingEntryWarnings(m, readings)) m.warnings.push_back(std::move(w));
  addUnsupportedCorrectionWarning(m);
  return m;
}

}  // namespace lidarcal::calibration
