#include "calibration/calibrate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <tuple>

#include <Eigen/Dense>

#include "calibration/inversion.hpp"
#include "calibration/jackknife.hpp"
#include "calibration/noise_exponent.hpp"
#include "common/parallel.hpp"
#include "common/plural.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {
namespace {

/// Position of each scan within its stop (0, 1, 2, ...), from the sightings.
std::map<std::size_t, std::size_t> scanPositions(const LandmarkObservations& obs) {
  std::map<std::size_t, std::set<std::size_t>> scans_of_stop;
  for (const auto& s : obs.sightings) scans_of_stop[s.stop].insert(s.scan);
  std::map<std::size_t, std::size_t> pos;
  for (const auto& [stop, scans] : scans_of_stop) {
    std::size_t i = 0;
    for (std::size_t scan : scans) pos[scan] = i++;
  }
  return pos;
}

std::map<std::size_t, std::size_t> scansPerStop(const LandmarkObservations& obs) {
  std::map<std::size_t, std::set<std::size_t>> scans_of_stop;
  for (const auto& s : obs.sightings) scans_of_stop[s.stop].insert(s.scan);
  std::map<std::size_t, std::size_t> n;
  for (const auto& [stop, scans] : scans_of_stop) n[stop] = scans.size();
  return n;
}

/// Largest distance between two stop positions (the triangulation baseline), metres.
double pathExtent(const std::vector<Pose2>& poses) {
  if (poses.empty()) return 0.0;
  double min_x = poses.front().x_m, max_x = min_x, min_y = poses.front().y_m, max_y = min_y;
  for (const auto& p : poses) {
    min_x = std::min(min_x, p.x_m);
    max_x = std::max(max_x, p.x_m);
    min_y = std::min(min_y, p.y_m);
    max_y = std::max(max_y, p.y_m);
  }
  return std::hypot(max_x - min_x, max_y - min_y);
}

/// "n thing" or "n things".
std::string count(std::size_t n, const std::string& thing) {
  return std::to_string(n) + " " + thing + (n == 1 ? "" : "s");
}

std::string metres(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f m", v);
  return buf;
}

/// Noise parameters of the requested law for a given bias, from (d, y) pairs.
NoiseModel fitNoiseLaw(NoiseKind kind, int order, const BiasPolynomial& f, const std::vector<double>& d,
                       const std::vector<double>& y) {
  NoiseModel n;
  n.kind = kind;
  std::vector<double> r(d.size());
  for (std::size_t i = 0; i < d.size(); ++i) r[i] = y[i] - f(d[i]);
  switch (kind) {
    case NoiseKind::squared: {
      double s = 0.0;
      for (std::size_t i = 0; i < d.size(); ++i) {
        const double fd = f(d[i]);
        s += r[i] * r[i] / (fd * fd * fd * fd);
      }
      n.sigma_e = std::sqrt(s / static_cast<double>(d.size()));
      break;
    }
    case NoiseKind::polynomial: n.beta = fitNoisePolynomial(d, r, std::max(order, 0)); break;
    case NoiseKind::constant: {
      double s = 0.0;
      for (double v : r) s += v * v;
      n.sigma_e = std::sqrt(s / static_cast<double>(r.size()));
      break;
    }
    default: throw std::invalid_argument("calibrate: noise law must be squared, polynomial or constant");
  }
  return n;
}

/// Runs one informational side estimator; a failure (degenerate data) is noted in `failed`, not
/// thrown: the calibration does not depend on it.
template <class Fn>
void sideEstimator(std::map<std::string, std::string>& failed, const char* name, Fn&& fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    failed[name] = e.what();
  }
}

/// The noise estimators side by side. Two independent groups run on up to `threads` threads:
/// seed 000's noise polynomial, and seed 004's closed form, its ML and the exponent test; each
/// writes only its own fields and failure notes, merged afterwards.
void fillNoiseFits(CalibrationModel& m, int order, const std::vector<double>& d, const std::vector<double>& y,
                   const std::vector<std::vector<double>>& batches, int threads) {
  NoiseFits& nf = m.noise_fits;
  nf = NoiseFits{};
  std::vector<double> r(d.size());
  for (std::size_t i = 0; i < d.size(); ++i) r[i] = y[i] - m.model.bias(d[i]);
  const int noise_order = std::max(order, 1), bias_order = std::max(order, 1);
  std::map<std::string, std::string> failed[2];
  parallelFor(2, threadsFor(threads), [&](std::size_t group) {
    if (group == 0) {
      sideEstimator(failed[0], "seed000_beta", [&] { nf.seed000_beta = fitNoisePolynomial(d, r, noise_order); });
      return;
    }
    sideEstimator(failed[1], "seed004_closed_form", [&] {
      const Seed004Fit cf = fitSeed004ClosedForm(d, y, bias_order);
      nf.seed004_cf_alpha = cf.alpha;
      nf.seed004_cf_sigma_e = cf.sigma_e;
    });
    if (!nf.seed004_cf_alpha.empty()) {
      sideEstimator(failed[1], "seed004_ml", [&] {
        const Seed004Fit ml = fitSeed004ML(d, y, nf.seed004_cf_alpha);
        nf.seed004_ml_alpha = ml.alpha;
        nf.seed004_ml_sigma_e = ml.sigma_e;
      });
    } else {
      failed[1]["seed004_ml"] = "starts from the closed form, which could not run";
    }
    sideEstimator(failed[1], "exponent_test", [&] {
      const NoiseExponentTest t = testNoiseExponent(batches);
      nf.exponent_loglik = t.log_likelihood;
      nf.exponent_best = t.best;
      nf.exponent_batches = t.batches;
    });
  });
  for (const auto& f : failed) nf.unavailable.insert(f.begin(), f.end());
}

void fillOrders(CalibrationModel& m, const OrderSelection& sel, std::size_t n) {
  m.orders.clear();
  for (const auto& row : sel.table) {
    OrderRow o;
    o.invertible = row.admissible;
    o.order = row.order;
    o.alpha = row.alpha;
    o.aic = row.aic;
    o.bic = row.aic - 2.0 * (row.order + 2.0) + (row.order + 2.0) * std::log(static_cast<double>(n));
    o.validation_mse_m2 = row.validation_mse_m2;
    o.test_mse_m2 = row.test_mse_m2;
    m.orders.push_back(o);
  }
  m.order_aic = sel.order_aic;
  m.order_validation = sel.order_validation;
  m.order_rule = toString(sel.rule);
}

double rmsResidual(const BiasPolynomial& f, const std::vector<double>& d, const std::vector<double>& y) {
  double s = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) s += std::pow(y[i] - f(d[i]), 2);
  return d.empty() ? 0.0 : std::sqrt(s / static_cast<double>(d.size()));
}

/// Starting centres for the joint refinement: bearing-only triangulation places far landmarks
/// poorly along the line of sight, so start each triangulated landmark at the mean of
/// commanded stop + (f^-1(central reading) + radius) along the bearing, with the closed-form f.
std::map<int, Eigen::Vector2d> rangeBearingCentres(const LandmarkObservations& obs,
                                                   const std::vector<LandmarkEstimate>& tri, const RangeModel& model,
                                                   double radius) {
  std::map<int, Eigen::Vector2d> sum;
  std::map<int, int> count;
  std::optional<RangeInverter> inverter;
  try {
    inverter.emplace(model, inversionWindow(model, InversionMethod::ls));
  } catch (const std::invalid_argument&) {
  }
  for (const auto& l : tri) {
    if (!l.ok()) continue;
    sum[l.id] = Eigen::Vector2d::Zero();
    count[l.id] = 0;
  }
  for (const auto& s : obs.sightings) {
    auto it = sum.find(s.landmark);
    if (it == sum.end() || s.beams.empty() || !inverter) continue;
    const auto d = inverter->invert(s.beams[centralBeam(s)].range_m);
    if (!d) continue;
    const Pose2& p = obs.commanded.at(s.stop);
    const double a = p.yaw_rad + s.bearing_rad;
    it->second += Eigen::Vector2d(p.x_m + (*d + radius) * std::cos(a), p.y_m + (*d + radius) * std::sin(a));
    ++count[s.landmark];
  }
  std::map<int, Eigen::Vector2d> out;
  for (const auto& l : tri) {
    if (!l.ok()) continue;
    out[l.id] = count[l.id] > 0 ? Eigen::Vector2d(sum[l.id] / count[l.id]) : Eigen::Vector2d(l.x_m, l.y_m);
  }
  return out;
}

/// The estimated effect terms that were switched on, by name (model.json "effects").
std::map<std::string, double> effectValues(const JointEffects& on, const JointEffectEstimates& e) {
  std::map<std::string, double> m;
  if (on.landmark_offsets)
    for (const auto& [id, o] : e.landmark_offset_m) m["landmark_offset_m[" + std::to_string(id) + "]"] = o;
  if (on.drift) {
    m["range_drift_m_per_scan"] = e.drift_m_per_scan;
    m["range_drift_reference_scan"] = e.drift_reference_scan;
  }
  if (on.angle_offset) m["angle_offset_rad"] = e.angle_offset_rad;
  if (on.incidence_bias) m["incidence_bias_m"] = e.incidence_bias_m;
  if (on.incidence_noise) m["incidence_noise_exponent"] = e.incidence_noise_exponent;
  if (on.noise_exponent) m["noise_exponent"] = e.noise_exponent;
  if (on.mixed_pixels) m["mixed_pixel_fraction"] = e.mixed_pixel_fraction;
  if (on.odometry_scale) m["odometry_scale"] = e.odometry_scale;
  if (on.student_noise) m["noise_student_dof"] = e.student_dof;
  if (on.quantised) m["range_resolution_m"] = e.range_grid_m;
  if (on.dark_noise) {
    m["dark_noise_exponent"] = e.dark_noise_exponent;
    m["dark_reference_intensity"] = e.dark_reference_intensity;
  }
  return m;
}

/// Orders whose f cannot be inverted over the sensor's reading window are not candidates: the
/// filtering stage could not use them (and they only arise from overfitting).
Admissible invertibleOver(double range_min_m, double range_max_m) {
  return [=](const std::vector<double>& alpha) {
    return alpha.size() >= 2 && invertsReadingWindow(BiasPolynomial{alpha}, range_min_m, range_max_m);
  };
}

/// RMS angle between the measured bearing lines and the triangulated centres (sigma_theta).
double bearingScatter(const LandmarkObservations& obs, const std::vector<LandmarkEstimate>& tri) {
  double s = 0.0;
  std::size_t n = 0;
  for (const auto& l : tri) {
    if (!l.ok()) continue;
    for (const auto& sb : stopBearings(obs, l.id)) {
      const Pose2& p = obs.commanded[sb.stop];
      const double predicted = std::atan2(l.y_m - p.y_m, l.x_m - p.x_m);
      s += std::pow(wrapAngle(sb.bearing_world_rad - predicted), 2);
      ++n;
    }
  }
  return n ? std::sqrt(s / static_cast<double>(n)) : 0.0;
}

/// The joint refinement's result at the chosen order, the order table and the AIC's choice.
struct JointStage {
  JointResult result;
  std::vector<OrderRow> rows;
  std::size_t best_aic = 0;  ///< index (order - 1) of the smallest admissible AIC
};

/// Stage 3: pass 1 settles the geometry at order 2; pass 2 fits every order from there on one
/// fixed set of readings (so their likelihoods compare the same data) and picks one by the
/// rule; the covariance is computed at the chosen order.
JointStage jointStage(const LandmarkObservations& obs, const CalibrationConfig& config,
                      const std::vector<LandmarkEstimate>& tri, const OrderSelection& sel, double radius,
                      const std::vector<double>& d, const std::vector<double>& y, const RangeModel& closed_form_model) {
  // Start from the closed form's straight-line fit: a higher order chosen by AIC on noisy
  // pairs can extrapolate wildly, a line is a safe start for the bias and the centres.
  JointInit init;
  init.poses = obs.commanded;
  init.model = closed_form_model;
  init.model.bias.alpha = sel.table[std::min<std::size_t>(1, sel.table.size() - 1)].alpha;
  init.model.noise = fitNoiseLaw(config.noise, 1, init.model.bias, d, y);
  init.centres = rangeBearingCentres(obs, tri, init.model, radius);
  init.radius_m = radius;
  JointConfig jc = config.joint;
  jc.noise = config.noise;
  jc.estimate_radius = !obs.landmark_radius_m.has_value();
  auto alphaAt = [&](int n, std::vector<double> alpha) {
    alpha.resize(static_cast<std::size_t>(n) + 1, 0.0);
    return alpha;
  };
  // Progress: the settling pass, one solve per order, the covariance.
  const std::size_t solves = 1 + static_cast<std::size_t>(config.max_order) + (config.joint.covariance ? 1 : 0);
  auto report = [&](std::size_t done) {
    if (config.progress) config.progress("joint refinement", done, solves);
  };
  report(0);
  // Pass 1: settle the geometry at order 2 (1 if max_order is 1).
  jc.order = std::min(2, config.max_order);
  init.model.bias.alpha = alphaAt(jc.order, init.model.bias.alpha);
  const JointResult settled = refineJoint(obs, init, jc);
  report(1);
  if (!settled.ok()) return JointStage{settled, {}, 0};
  // Pass 2: every order from the settled geometry on one fixed set of readings, so that their
  // information criteria compare likelihoods of the same data.
  JointInit from = init;
  from.poses = settled.poses;
  from.centres = settled.centres;
  from.radius_m = settled.radius_m;
  from.model = settled.model;
  from.effects = settled.effects;
  jc.reselect = false;
  jc.covariance = false;  // computed once, for the chosen order
  jc.outer_iterations = std::min(jc.outer_iterations, 2);  // the noise law settled in pass 1
  std::vector<JointResult> runs;
  std::vector<OrderRow> rows;
  // The orders are independent solves: side by side, each with its own copy of the settings.
  runs.resize(static_cast<std::size_t>(config.max_order));
  parallelFor(runs.size(), threadsFor(config.threads), [&](std::size_t k) {
    JointConfig jn = jc;
    JointInit fn = from;
    jn.order = static_cast<int>(k) + 1;
    fn.model.bias.alpha = alphaAt(jn.order, settled.model.bias.alpha);
    runs[k] = refineJoint(obs, fn, jn);
  });
  for (int n = 1; n <= config.max_order; ++n) {
    report(1 + static_cast<std::size_t>(n));
    const auto& r = runs[static_cast<std::size_t>(n) - 1];
    OrderRow row;
    row.order = n;
    row.alpha = r.model.bias.alpha;
    row.aic = r.aic;
    row.bic = r.bic;
    row.validation_mse_m2 = row.test_mse_m2 = std::numeric_limits<double>::quiet_NaN();
    rows.push_back(row);
  }
  const bool window_known = obs.range_max_m < 1e8;
  const Admissible ok_order = window_known ? invertibleOver(obs.range_min_m, obs.range_max_m) : Admissible{};
  for (auto& row : rows) row.invertible = !ok_order || ok_order(row.alpha);
  std::size_t best_aic = 0, best_bic = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!rows[i].invertible) continue;
    if (!rows[best_aic].invertible || runs[i].aic < runs[best_aic].aic) best_aic = i;
    if (!rows[best_bic].invertible || runs[i].bic < runs[best_bic].bic) best_bic = i;
  }
  std::size_t chosen = best_aic;
  if (config.joint_rule == JointOrderRule::bic) chosen = best_bic;
  if (config.joint_rule == JointOrderRule::aic_parsimonious)
    for (std::size_t i = 0; i < runs.size(); ++i)
      if (rows[i].invertible && runs[i].aic <= runs[best_aic].aic + 2.0) {
        chosen = i;
        break;
      }
  if (config.joint.covariance && runs[chosen].ok()) {
    // Covariance at the chosen order: one more (already converged) solve with it switched on.
    JointInit at = from;
    at.poses = runs[chosen].poses;
    at.centres = runs[chosen].centres;
    at.radius_m = runs[chosen].radius_m;
    at.model = runs[chosen].model;
    at.effects = runs[chosen].effects;
    jc.order = static_cast<int>(chosen) + 1;
    jc.covariance = true;
    jc.outer_iterations = 1;
    runs[chosen] = refineJoint(obs, at, jc);
  }
  report(solves);
  return JointStage{runs[chosen], rows, best_aic};
}

}  // namespace

void addUnsupportedCorrectionWarning(CalibrationModel& m) {
  const std::size_t n = m.model.bias.alpha.size();
  if (!m.fitted_range_m || m.alpha_covariance.size() != n * n) return;
  const auto [lo, hi] = *m.fitted_range_m;
  double largest = 0.0, largest_se = 0.0;
  for (int i = 0; i <= 50; ++i) {
    const double d = lo + (hi - lo) * i / 50.0;
    // Standard error of f(d): that of the distance it corrects to, times f'(d).
    const double se = correctionStandardError(m.model.bias, m.alpha_covariance, d, d, d) * m.model.bias.derivative(d);
    const double c = std::abs(m.model.bias(d) - d);
    if (!std::isfinite(se)) return;
    if (c > 2.0 * se) return;  // a correction the data support somewhere
    if (c > largest) largest = c, largest_se = se;
  }
  char text[400];
  std::snprintf(text, sizeof text,
                "the correction is within two standard errors of none over the whole fitted range (at most %.1f mm, "
                "+-%.1f mm there): the data do not show that the sensor errs, and applying it may add as much error as "
                "it removes; measure more distances, or repeat each, before relying on it",
                1000.0 * largest, 1000.0 * largest_se);
  m.warnings.push_back(text);
}

void addPlausibilityWarnings(CalibrationModel& m, const JointResult* j) {
  const std::size_t n = m.model.bias.alpha.size();
  char text[512];
  addUnsupportedCorrectionWarning(m);
  // An offset that trades off against the pole radius is not determined by the data: the
  // central beam reads alpha_0 + alpha_1 (|c - p| - r), and only the arcs' curvature tells r.
  if (j && j->alpha_radius_covariance.size() == static_cast<Eigen::Index>(n) && j->radius_variance > 0.0 &&
      m.alpha_covariance.size() == n * n && m.alpha_covariance[0] > 0.0) {
    const double corr = j->alpha_radius_covariance(0) / std::sqrt(m.alpha_covariance[0] * j->radius_variance);
    m.offset_radius_correlation = corr;
    if (std::abs(corr) > 0.9) {
      std::snprintf(text, sizeof text,
                    "the offset alpha_0 = %.1f mm (+-%.1f) trades off against the estimated pole radius %.1f mm "
                    "(correlation %.2f): the data do not separate them, so the offset is not determined; measure the "
                    "poles' radius and give it with --radius (or calibrate against measured distances, --reference)",
                    1000.0 * m.model.bias.alpha[0], 1000.0 * std::sqrt(m.alpha_covariance[0]), 1000.0 * j->radius_m, corr);
      m.warnings.push_back(text);
    }
  }
  // Landmarks the data do not locate: with a centre uncertain by decimetres the range offset
  // can trade against where the landmark stands, and a small standard error of the offset does
  // not mean it is right. Every CARMEN office log gives this (median centre standard error
  // 0.4-90 m: its "landmarks" are furniture seen from few directions), the simulated pole fields
  // about 1 cm.
  if (j && !j->centre_covariance.empty()) {
    std::vector<double> se;
    for (const auto& [id, c] : j->centre_covariance)
      se.push_back(std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(c).eigenvalues()(1))));
    const double typical = median(se);
    if (typical > kUnlocatedLandmarkM) {
      std::snprintf(text, sizeof text,
                    "the landmarks' positions are not pinned down by the data (median standard error of a centre "
                    "%.2f m over %s, against about 0.01 m for round poles seen from several stops): the "
                    "offset can trade against where they stand, so its standard error understates its error; check "
                    "that lidarcal detect finds round poles of one radius, record stops all around them, or "
                    "calibrate against measured distances (--reference)",
                    typical, plural(se.size(), "landmark").c_str());
      m.warnings.push_back(text);
    }
  }
  // Corrections far beyond what lidars are built to: more often landmarks that are not round
  // poles of one radius (corners, door frames) than a sensor that far off. The bound leaves
  // room for the strongly biased triangulation sensor of Alhashimi et al. 2021's simulations
  // (alpha = [0.0525, 0.8838, 0.0584]: +17 % at 4.9 m), which is not an error.
  if (m.fitted_range_m) {
    const auto [lo, hi] = *m.fitted_range_m;
    double worst = 0.0, at = lo;
    for (int i = 0; i <= 50; ++i) {
      const double d = lo + (hi - lo) * i / 50.0;
      const double rel = std::abs(m.model.bias(d) - d) / std::max(d, 0.5);
      if (rel > worst) worst = rel, at = d;
    }
    if (worst > kImplausibleCorrection) {
      std::snprintf(text, sizeof text,
                    "the model changes readings by up to %.0f %% (%.0f mm at %.2f m): more than the range error of "
                    "most lidars; check that the landmarks lidarcal detect finds are round poles of one radius (not "
                    "corners, door frames or legs of different sizes) before using it",
                    100.0 * worst, 1000.0 * std::abs(m.model.bias(at) - at), at);
      m.warnings.push_back(text);
    }
  }
}

const char* toString(Method m) { return m == Method::closed_form ? "closed-form" : "joint"; }

const char* toString(JointOrderRule r) {
  switch (r) {
    case JointOrderRule::aic: return "aic";
    case JointOrderRule::aic_parsimonious: return "aic-parsimonious";
    case JointOrderRule::bic: return "bic";
  }
  return "unknown";
}

void CalibrationConfig::validate() const {
  if (max_order < 1 || max_order > 6) throw std::invalid_argument("CalibrationConfig: max_order must be 1..6");
  if (threads < 0) throw std::invalid_argument("CalibrationConfig: threads must be >= 0 (0: automatic)");
  triangulation.validate();
  JointConfig j = joint;
  j.order = 1;
  j.noise = noise;
  j.validate();
}

std::optional<std::string> baselineProblem(const std::vector<Pose2>& stops, const CalibrationConfig& config) {
  const double baseline = pathExtent(stops);
  if (stops.size() < 2 || baseline >= config.min_baseline_m) return std::nullopt;
  return "the " + count(stops.size(), "stop") + " lie within " + metres(baseline) +
         " of each other (the sensor turned or stood still), so the landmarks cannot be placed from their bearings: "
         "record stops along a straight line of at least 1 m (a quarter of the distance to the poles or more), or "
         "give measured distances with --reference (docs/FORMAT.md)";
}

double landmarkRadius(const LandmarkObservations& obs) {
  if (obs.landmark_radius_m) return *obs.landmark_radius_m;
  std::vector<double> r;
  for (const auto& s : obs.sightings)
    if (s.radius_m > 0.0) r.push_back(s.radius_m);
  return median(r);
}

std::vector<RangePair> closedFormPairs(const LandmarkObservations& obs, const std::vector<LandmarkEstimate>& landmarks,
                                       double radius_m, bool per_scan) {
  std::map<int, const LandmarkEstimate*> ok;
  for (const auto& l : landmarks)
    if (l.ok()) ok[l.id] = &l;
  const auto position = scanPositions(obs);
  const auto per_stop = scansPerStop(obs);
  struct Acc {
    double d = 0, y = 0;
    int n = 0;
  };
  std::map<std::tuple<int, std::size_t, int>, Acc> groups;  // (landmark, stop, part)
  std::vector<RangePair> pairs;
  for (const auto& s : obs.sightings) {
    auto it = ok.find(s.landmark);
    if (it == ok.end() || s.beams.empty()) continue;
    const BeamReading& b = s.beams[centralBeam(s)];
    if (!std::isfinite(b.range_m)) continue;
    const Pose2& p = obs.commanded.at(s.stop);
    const double d = rayCircleDistance(p.x_m, p.y_m, p.yaw_rad + b.angle_rad, it->second->x_m, it->second->y_m, radius_m);
    // A beam that meets the triangulated circle behind the stop (or at it) cannot have read this
    // landmark: the triangulation placed it badly. Such a pair says nothing about f.
    if (!(d > 0.0) || !std::isfinite(d)) continue;
    // The paper's split (seed 000 section 4.3) into fit / choose / test thirds: by scan within
    // the stop when a stop has at least three scans, else by (landmark, stop).
    const int part = per_stop.at(s.stop) >= 3 ? static_cast<int>(position.at(s.scan) % 3)
                                               : static_cast<int>((s.stop + static_cast<std::size_t>(s.landmark)) % 3);
    if (per_scan) {
      pairs.push_back({d, b.range_m, part});
    } else {
      Acc& a = groups[{s.landmark, s.stop, part}];
      a.d += d;
      a.y += b.range_m;
      ++a.n;
    }
  }
  for (const auto& [key, a] : groups) pairs.push_back({a.d / a.n, a.y / a.n, std::get<2>(key)});
  return pairs;
}

std::vector<std::vector<double>> constantDistanceBatches(const LandmarkObservations& obs) {
  std::map<std::tuple<std::size_t, int, std::uint32_t>, std::vector<std::pair<std::size_t, double>>> by_beam;
  for (const auto& s : obs.sightings)
    for (const auto& b : s.beams)
      if (std::isfinite(b.range_m) && b.beam != kUnknownBeam)
        by_beam[{s.stop, s.landmark, b.beam}].push_back({s.scan, b.range_m});
  std::vector<std::vector<double>> batches;
  for (auto& [key, v] : by_beam) {
    std::sort(v.begin(), v.end());
    std::vector<double> y;
    for (const auto& [scan, r] : v) y.push_back(r);
    batches.push_back(std::move(y));
  }
  return batches;
}

namespace {

/// Stage 1 into the model: one landmark per triangulated one; returns how many are usable.
int addTriangulated(CalibrationModel& m, const std::vector<LandmarkEstimate>& tri, double radius) {
  int usable = 0;
  for (const auto& l : tri) {
    CalibratedLandmark c;
    c.id = l.id;
    c.x_m = l.x_m;
    c.y_m = l.y_m;
    c.radius_m = radius;
    c.covariance_m2 = {l.covariance(0, 0), l.covariance(0, 1), l.covariance(1, 0), l.covariance(1, 1)};
    c.stops = l.stops;
    c.status = l.ok() ? "ok" : std::string(toString(l.status)) + ": " + l.message;
    m.landmarks.push_back(c);
    usable += l.ok();
  }
  return usable;
}

/// The refusal when no landmark could be triangulated: the first three reasons, what to record.
void refuseNoUsableLandmark(CalibrationModel& m, const std::vector<LandmarkEstimate>& tri) {
  m.status.code = StatusCode::no_usable_landmark;
  m.status.message = tri.empty() ? "no landmark was observed (check what lidarcal detect finds)"
                          : "no landmark could be triangulated";
  for (std::size_t i = 0; i < tri.size() && i < 3; ++i) m.status.message += "; landmark " + std::to_string(tri[i].id) + ": " + m.landmarks[i].status;
  if (tri.size() > 3) m.status.message += "; and " + std::to_string(tri.size() - 3) + " more";
  m.status.message += ". Record 3 or more stops along a straight line past 3 or more poles (cylinders 5-30 cm across, "
               "free-standing, 0.5-4 m away), give their radius with --radius if they are thinner, or give measured "
               "distances with --reference";
}

/// The refusal when too few landmark-stop distances came out of the triangulation.
void refuseTooFewObservations(CalibrationModel& m, const LandmarkObservations& obs, const CalibrationConfig& config,
                              const std::vector<LandmarkEstimate>& tri, std::size_t pairs, int usable,
                              double baseline) {
  std::size_t read = 0;  // sightings with a finite central reading on a triangulated landmark
  for (const auto& s : obs.sightings)
    for (const auto& l : tri)
      if (l.ok() && l.id == s.landmark && !s.beams.empty() && std::isfinite(s.beams[centralBeam(s)].range_m)) ++read;
  m.status.code = StatusCode::too_few_observations;
  m.status.message = "only " + count(pairs, "landmark-stop distance") + " from " + count(static_cast<std::size_t>(usable), "triangulated landmark") +
              " (at least " + std::to_string(config.max_order + 3) + " needed)";
  if (read > 0 && pairs == 0)
    m.status.message += ": none of the " + count(read, "reading") +
                 " meets its triangulated landmark in front of the sensor, so the bearing-only positions are wrong "
                 "(a path of " + metres(baseline) + " is short for landmarks this far)";
  m.status.message += ": record more stops along a longer straight line past 3 or more poles, or give measured distances with "
               "--reference";
}

/// Stage 2 into the model: order, bias, noise law and the side estimators from the per-scan
/// landmark-stop pairs (d, y), which it returns for the joint refinement.
void fillClosedForm(CalibrationModel& m, const LandmarkObservations& obs, const std::vector<LandmarkEstimate>& tri,
                    const OrderSelection& sel, std::size_t n_pairs, const std::vector<RangePair>& scan_pairs,
                    const CalibrationConfig& config, const std::vector<std::vector<double>>& batches,
                    std::vector<double>& d, std::vector<double>& y) {
  fillOrders(m, sel, n_pairs);
  for (const auto& p : scan_pairs) {
    d.push_back(p.d_m);
    y.push_back(p.y_m);
  }
  const int order = std::max(sel.chosen, 1);  // order 0 cannot be inverted
  m.model.bias.alpha = sel.table[static_cast<std::size_t>(std::min<int>(order, static_cast<int>(sel.table.size()) - 1))].alpha;
  m.model.noise = fitNoiseLaw(config.noise, order, m.model.bias, d, y);
  // The noise estimators side by side: the joint refinement fits them again on its own readings
  // (fillJoint), so they are fitted here only for a model that stays a closed form.
  if (config.method == Method::closed_form) fillNoiseFits(m, order, d, y, batches, config.threads);
  m.residual_rms_m = rmsResidual(m.model.bias, d, y);
  m.readings = d.size();
  m.sigma_theta_rad = bearingScatter(obs, tri);
  m.stop_poses = obs.commanded;
  m.fitted_range_m = fittedRange(d, y, m.model.bias);
}

/// Groups of the delete-a-group jackknife of the closed form: at most this many, each a run of
/// consecutive stops (a stop each when there are fewer stops).
constexpr std::size_t kClosedFormJackknifeGroups = 20;

/// Covariance of the closed form's bias at `order` (row-major): the delete-a-group jackknife over
/// the stops, (G - 1)/G sum_g (alpha_-g - mean)(alpha_-g - mean)^T, each alpha_-g from the
/// triangulation and the fit redone without group g. Seed 000's closed form has no covariance
/// of its own (its distances are themselves estimated from the same data); this one includes
/// the triangulation's error. Empty when fewer than 3 groups leave enough pairs.
std::vector<double> closedFormCovariance(const LandmarkObservations& obs, const CalibrationConfig& config, double radius,
                                         int order) {
  std::vector<std::size_t> stops;
  for (const auto& s : obs.sightings) stops.push_back(s.stop);
  std::sort(stops.begin(), stops.end());
  stops.erase(std::unique(stops.begin(), stops.end()), stops.end());
  const std::size_t G = std::min(stops.size(), kClosedFormJackknifeGroups);
  if (G < 3) return {};
  std::map<std::size_t, std::size_t> group;  // stop -> group
  for (std::size_t k = 0; k < stops.size(); ++k) group[stops[k]] = k * G / stops.size();
  const std::size_t n = static_cast<std::size_t>(order) + 1;
  std::vector<Eigen::VectorXd> alphas;
  for (std::size_t g = 0; g < G; ++g) {
    LandmarkObservations without = obs;
    without.sightings.clear();
    for (const auto& s : obs.sightings)
      if (group[s.stop] != g) without.sightings.push_back(s);
    const auto pairs = closedFormPairs(without, triangulateAll(without, config.triangulation), radius, false);
    if (pairs.size() < n + 2) return {};
    const OrderSelection sel = selectOrder(pairs, order, config.closed_form_rule);
    const auto& a = sel.table[static_cast<std::size_t>(order)].alpha;
    if (a.size() != n) return {};
    alphas.push_back(Eigen::Map<const Eigen::VectorXd>(a.data(), static_cast<Eigen::Index>(n)));
  }
  const Eigen::MatrixXd cov = jackknifeCovariance(alphas);
  std::vector<double> out(n * n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) out[i * n + j] = cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
  return out;
}

/// Refuses a joint refinement that failed, or that ran away: a solution placing a landmark where
/// the sensor could not have read it (distances far beyond its range limit) has moved along a
/// direction the data do not pin down (seen with a single landmark: its centre, the bias and the
/// poses trade off). True when refused.
bool refuseJoint(CalibrationModel& m, const JointResult& j, const LandmarkObservations& obs, int usable,
                 double baseline) {
  if (!j.ok()) {
    m.status.code = StatusCode::joint_failed;
    m.status.message = j.status.message + " (" + count(static_cast<std::size_t>(usable), "landmark") + " triangulated over a path of " +
                metres(baseline) + ": the beams that saw them do not meet the triangulated circles). Record stops along "
                "a longer straight line past 3 or more poles, give the pole radius (--radius), or use --method "
                "closed-form";
    return true;
  }
  const auto [near, far] = std::minmax_element(j.distances_m.begin(), j.distances_m.end());
  if (far == j.distances_m.end()) return false;
  const std::string advice =
      " (too little geometry to pin it down: record more stops along a longer line past more poles, or use --method "
      "closed-form)";
  if (!(*near > 0.0)) {
    // Collapsed: the landmarks moved onto the stops, and a bias of any slope explains readings at
    // zero distance (seen on a YDLIDAR recording of four poles: slope -776).
    m.status.code = StatusCode::joint_failed;
    m.status.message = "the joint refinement collapsed: it places a landmark at a stop (a beam distance of " +
                std::to_string(*near) + " m)" + advice;
    return true;
  }
  if (!isMonotone(j.model.bias, *near, *far)) {
    m.status.code = StatusCode::joint_failed;
    m.status.message = "the joint refinement's bias falls with distance somewhere in " + std::to_string(*near) + "-" +
                std::to_string(*far) + " m, where it saw the landmarks, so no reading there has one distance" + advice;
    return true;
  }
  if (!(obs.range_max_m < 1e8)) return false;
  const double limit = 1.5 * obs.range_max_m + 0.5;
  if (*far <= limit) return false;
  m.status.code = StatusCode::joint_failed;
  m.status.message = "the joint refinement ran away: it places a landmark " + std::to_string(*far) +
              " m from a stop, beyond the sensor's range limit of " + std::to_string(obs.range_max_m) + " m" + advice;
  return true;
}

/// Stage 3 into the model: the joint refinement's model, poses, landmarks and diagnostics.
void fillJoint(CalibrationModel& m, const JointStage& js, const CalibrationConfig& config,
               const std::vector<std::vector<double>>& batches) {
  const JointResult& j = js.result;
  m.orders = js.rows;
  m.order_rule = toString(config.joint_rule);
  m.order_aic = static_cast<int>(js.best_aic) + 1;
  m.order_validation = -1;
  m.model.bias = j.model.bias;
  m.model.noise = j.model.noise;
  m.sigma_theta_rad = j.sigma_theta_rad;
  m.iterations = j.solver_iterations;
  m.readings = j.readings;
  m.pose_scatter_m = j.pose_scatter_m;
  m.motion_prior = j.motion_prior;
  m.stop_poses = j.poses;
  m.heading_scatter_rad = j.heading_scatter_rad;
  m.residual_rms_m = j.residual_rms_m;
  // The noise estimators side by side, on the joint refinement's readings and distances.
  fillNoiseFits(m, m.model.bias.order(), j.distances_m, j.readings_m, batches, config.threads);
  m.alpha_covariance.assign(j.alpha_covariance.data(), j.alpha_covariance.data() + j.alpha_covariance.size());
  m.effects = effectValues(config.joint.effects, j.effects);
  for (auto& c : m.landmarks) {
    auto it = j.centres.find(c.id);
    if (it == j.centres.end()) continue;
    c.x_m = it->second.x();
    c.y_m = it->second.y();
    c.radius_m = j.radius_m;
    auto cv = j.centre_covariance.find(c.id);
    if (cv != j.centre_covariance.end())
      c.covariance_m2 = {cv->second(0, 0), cv->second(0, 1), cv->second(1, 0), cv->second(1, 1)};
  }
  if (!j.distances_m.empty()) m.fitted_range_m = fittedRange(j.distances_m, j.readings_m, m.model.bias);
  if (!j.converged) m.status.message = "joint refinement: " + j.status.message;  // usable, but say so
}

}  // namespace

CalibrationModel calibrate(const LandmarkObservations& obs, const CalibrationConfig& config) {
  config.validate();
  CalibrationModel m;
  m.method = toString(config.method);
  m.model.range_min_m = obs.range_min_m;
  m.model.range_max_m = obs.range_max_m;

  // Triangulating from bearings needs the sensor to translate: stops at one place (a sensor
  // turning on the spot, or standing still) give every landmark the same bearing line.
  const double baseline = pathExtent(obs.commanded);
  if (const auto problem = baselineProblem(obs.commanded, config); problem && !obs.sightings.empty()) {
    m.status.code = StatusCode::no_baseline;
    m.status.message = *problem;
    return m;
  }

  // The dark-surface noise term fits the noise against the return intensity: nothing to fit without one.
  if (config.method == Method::joint && config.joint.effects.dark_noise && !intensitiesVary(obs)) {
    m.status.code = StatusCode::no_intensity;
    m.status.message = "--effects dark_surface fits the noise against the return intensity, and no reading of these "
                       "scans records one (or all record the same value): record with the driver's intensities on "
                       "(ROS LaserScan intensities, a PCD intensity field), or leave dark_surface out of --effects";
    return m;
  }

  // Stage 1: triangulation.
  const auto tri = triangulateAll(obs, config.triangulation);
  const double radius = landmarkRadius(obs);
  const int usable = addTriangulated(m, tri, radius);
  if (usable == 0) {
    refuseNoUsableLandmark(m, tri);
    return m;
  }
  if (!(radius > 0.0)) {
    m.status.code = StatusCode::no_radius;
    m.status.message = "the landmark radius is unknown and could not be estimated";
    return m;
  }

  // Stage 2: the paper's closed form.
  const auto pairs = closedFormPairs(obs, tri, radius, false);
  const auto scan_pairs = closedFormPairs(obs, tri, radius, true);
  if (pairs.size() < static_cast<std::size_t>(config.max_order) + 3) {
    refuseTooFewObservations(m, obs, config, tri, pairs.size(), usable, baseline);
    return m;
  }
  const bool window_known = obs.range_max_m < 1e8;
  const OrderSelection sel = selectOrder(pairs, config.max_order, config.closed_form_rule,
                                         window_known ? invertibleOver(obs.range_min_m, obs.range_max_m) : Admissible{});
  const auto batches = constantDistanceBatches(obs);
  std::vector<double> d, y;
  fillClosedForm(m, obs, tri, sel, pairs.size(), scan_pairs, config, batches, d, y);
  if (config.method == Method::closed_form) {
    m.alpha_covariance = closedFormCovariance(obs, config, radius, static_cast<int>(m.model.bias.alpha.size()) - 1);
    addPlausibilityWarnings(m, nullptr);
    return m;
  }

  // Stage 3: joint refinement (ours), from the closed form.
  const JointStage js = jointStage(obs, config, tri, sel, radius, d, y, m.model);
  if (refuseJoint(m, js.result, obs, usable, baseline)) {
    fillNoiseFits(m, std::max(sel.chosen, 1), d, y, batches, config.threads);  // the closed form's, as fillClosedForm skipped them
    return m;
  }
  fillJoint(m, js, config, batches);
  addPlausibilityWarnings(m, &js.result);
  return m;
}

CalibrationModel calibrateAgainstTruth(const std::vector<RangePair>& pairs, const CalibrationConfig& config,
                                       const std::vector<std::vector<double>>& batches, double range_min_m,
                                       double range_max_m) {
  config.validate();
  CalibrationModel m;
  m.method = "oracle";
  m.model.range_min_m = range_min_m;
  m.model.range_max_m = range_max_m;
  if (pairs.size() < static_cast<std::size_t>(config.max_order) + 3) {
    m.status.code = StatusCode::too_few_observations;
    m.status.message = "too few readings with a known distance";
    return m;
  }
  const Admissible window = range_max_m < 1e8 ? invertibleOver(range_min_m, range_max_m) : Admissible{};
  const OrderSelection sel = selectOrder(pairs, config.max_order, config.closed_form_rule, window);
  fillOrders(m, sel, pairs.size());
  std::vector<double> d, y;
  for (const auto& p : pairs) {
    d.push_back(p.d_m);
    y.push_back(p.y_m);
  }
  int order = std::max(sel.chosen, 1);
  if (config.noise == NoiseKind::squared) {
    // With known distances the oracle is seed 004's estimator: full ML of model (1) for every
    // order (eqs. 18-20, from the closed form eqs. 21-26) and the order by AIC on that likelihood.
    double best = std::numeric_limits<double>::infinity();
    for (auto& row : m.orders) {
      if (row.order < 1) continue;
      const Seed004Fit cf = fitSeed004ClosedForm(d, y, row.order);
      const Seed004Fit ml = fitSeed004ML(d, y, cf.alpha);
      const double k = row.order + 2.0;
      row.alpha = ml.alpha;
      row.aic = 2.0 * k + 2.0 * ml.neg_log_likelihood;
      row.bic = k * std::log(static_cast<double>(d.size())) + 2.0 * ml.neg_log_likelihood;
      row.invertible = !window || window(row.alpha);
      if (row.invertible && row.aic < best) {
        best = row.aic;
        order = row.order;
      }
    }
    m.order_aic = order;
    m.order_rule = "aic (seed 004 ML)";
    m.model.bias.alpha = m.orders[static_cast<std::size_t>(order)].alpha;
  } else {
    m.model.bias.alpha = sel.table[static_cast<std::size_t>(std::min<int>(order, static_cast<int>(sel.table.size()) - 1))].alpha;
  }
  fillNoiseFits(m, order, d, y, batches, config.threads);
  m.model.noise = fitNoiseLaw(config.noise, order, m.model.bias, d, y);
  m.residual_rms_m = rmsResidual(m.model.bias, d, y);
  m.readings = d.size();
  m.fitted_range_m = fittedRange(d, y, m.model.bias);
  return m;
}

}  // namespace lidarcal::calibration
