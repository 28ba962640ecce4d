#include "calibration/joint_refinement.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <tuple>

#include <ceres/ceres.h>

#include "calibration/range_model_fit.hpp"
#include "common/range_effects.hpp"

namespace lidarcal::calibration {
namespace {

constexpr double kLog2Pi = 1.8378770664093453;

/// Residual of one beam reading: (y - f(d(pose, centre, radius))) / sigma_i, N = order + 1.
template <int N>
struct BeamRangeCost {
  double angle_rad, y_m, inv_sigma;
  template <typename T>
  bool operator()(const T* pose, const T* centre, const T* radius, const T* alpha, T* residual) const {
    const T a = pose[2] + T(angle_rad);
    const T d = rayCircleDistance(pose[0], pose[1], a, centre[0], centre[1], radius[0]);
    T f = alpha[N - 1];
    for (int i = N - 2; i >= 0; --i) f = f * d + alpha[i];
    residual[0] = (T(y_m) - f) * T(inv_sigma);
    return true;
  }
};

/// The same with the effect terms in the mean: landmark offset o, and g = (drift c, zero-angle
/// offset a_0, incidence bias b); t_rel = t - t_ref.
template <int N>
struct EffectBeamCost {
  double angle_rad, y_m, inv_sigma, t_rel;
  template <typename T>
  bool operator()(const T* pose, const T* centre, const T* radius, const T* alpha, const T* offset, const T* g,
                  T* residual) const {
    using std::cos;
    using std::sin;
    using std::sqrt;
    const T a = pose[2] + T(angle_rad) + g[1];
    const T d = rayCircleDistance(pose[0], pose[1], a, centre[0], centre[1], radius[0]);
    T f = alpha[N - 1];
    for (int i = N - 2; i >= 0; --i) f = f * d + alpha[i];
    const T perp = (centre[1] - pose[1]) * cos(a) - (centre[0] - pose[0]) * sin(a);
    const T u = perp / radius[0];
    T c2 = T(1) - u * u;
    if (c2 < T(0.0025)) c2 = T(0.0025);  // clampCosIncidence
    const T mean = f + offset[0] + g[0] * T(t_rel) + g[2] * (T(1) - sqrt(c2));
    residual[0] = (T(y_m) - mean) * T(inv_sigma);
    return true;
  }
};

/// A weak prior of a point (a landmark centre) at (x, y) with standard deviation sigma.
struct WeakPointPriorCost {
  double x, y, sigma;
  template <typename T>
  bool operator()(const T* p, T* residual) const {
    residual[0] = (p[0] - T(x)) / T(sigma);
    residual[1] = (p[1] - T(y)) / T(sigma);
    return true;
  }
};
constexpr double kWeakCentrePriorSigmaM = 100.0;

/// Prior of a stop pose around its commanded value.
struct PosePriorCost {
  double x, y, yaw, inv_s, inv_psi;
  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    residual[0] = (pose[0] - T(x)) * T(inv_s);
    residual[1] = (pose[1] - T(y)) * T(inv_s);
    // Headings stay within a few degrees of the command: a plain difference is fine once the
    // commanded value is unwrapped next to the estimate (done when the pose is initialised).
    residual[2] = (pose[2] - T(yaw)) * T(inv_psi);
    return true;
  }
};

/// Prior of a stop pose around the commanded one with the step from stop 0 scaled by (1 + s).
struct ScaledPosePriorCost {
  double x, y, yaw, x0, y0, inv_s, inv_psi;
  template <typename T>
  bool operator()(const T* pose, const T* scale, T* residual) const {
    residual[0] = (pose[0] - (T(x0) + (T(1) + scale[0]) * T(x - x0))) * T(inv_s);
    residual[1] = (pose[1] - (T(y0) + (T(1) + scale[0]) * T(y - y0))) * T(inv_s);
    residual[2] = (pose[2] - T(yaw)) * T(inv_psi);
    return true;
  }
};

/// Motion prior between consecutive stops a -> b: the step from a to b in a's frame against
/// the commanded step (dx, dy, dpsi), its translation scaled by (1 + s) (odometry scale).
struct MotionPriorCost {
  double dx, dy, dpsi, inv_t, inv_psi;
  template <typename T>
  bool operator()(const T* a, const T* b, const T* scale, T* residual) const {
    using std::cos;
    using std::sin;
    const T c = cos(a[2]), s = sin(a[2]);
    const T ex = b[0] - a[0], ey = b[1] - a[1];
    const T f = T(1) + scale[0];
    residual[0] = (c * ex + s * ey - f * T(dx)) * T(inv_t);
    residual[1] = (c * ey - s * ex - f * T(dy)) * T(inv_t);
    // Like the pose prior: dpsi is unwrapped next to the estimate when the residual is built.
    residual[2] = (b[2] - a[2] - T(dpsi)) * T(inv_psi);
    return true;
  }
};

/// The commanded step from stop a to stop b, in a's frame.
Pose2 commandedStep(const Pose2& a, const Pose2& b) {
  Pose2 d;
  a.toSensor(b.x_m, b.y_m, d.x_m, d.y_m);
  d.yaw_rad = wrapAngle(b.yaw_rad - a.yaw_rad);
  return d;
}

template <int N>
ceres::CostFunction* makeBeamCost(double angle, double y, double inv_sigma) {
  return new ceres::AutoDiffCostFunction<BeamRangeCost<N>, 1, 3, 2, 1, N>(new BeamRangeCost<N>{angle, y, inv_sigma});
}

template <int N>
ceres::CostFunction* makeEffectCost(double angle, double y, double inv_sigma, double t_rel) {
  return new ceres::AutoDiffCostFunction<EffectBeamCost<N>, 1, 3, 2, 1, N, 1, 3>(
      new EffectBeamCost<N>{angle, y, inv_sigma, t_rel});
}

ceres::CostFunction* beamCost(int order, double angle, double y, double inv_sigma) {
  switch (order + 1) {
    case 2: return makeBeamCost<2>(angle, y, inv_sigma);
    case 3: return makeBeamCost<3>(angle, y, inv_sigma);
    case 4: return makeBeamCost<4>(angle, y, inv_sigma);
    case 5: return makeBeamCost<5>(angle, y, inv_sigma);
    case 6: return makeBeamCost<6>(angle, y, inv_sigma);
    case 7: return makeBeamCost<7>(angle, y, inv_sigma);
    default: throw std::invalid_argument("refineJoint: order must be 1..6");
  }
}

ceres::CostFunction* effectCost(int order, double angle, double y, double inv_sigma, double t_rel) {
  switch (order + 1) {
    case 2: return makeEffectCost<2>(angle, y, inv_sigma, t_rel);
    case 3: return makeEffectCost<3>(angle, y, inv_sigma, t_rel);
    case 4: return makeEffectCost<4>(angle, y, inv_sigma, t_rel);
    case 5: return makeEffectCost<5>(angle, y, inv_sigma, t_rel);
    case 6: return makeEffectCost<6>(angle, y, inv_sigma, t_rel);
    case 7: return makeEffectCost<7>(angle, y, inv_sigma, t_rel);
    default: throw std::invalid_argument("refineJoint: order must be 1..6");
  }
}

struct Reading {
  std::size_t stop;
  std::size_t scan;
  int landmark;
  double angle_rad;
  double y_m;
  bool edge;
};

/// Geometry of a beam at the current estimate: distance, cosine of the incidence, lateral offset.
struct BeamGeometry {
  double d = 0.0, cos_inc = 1.0, lateral = 0.0;
};

BeamGeometry beamGeometry(const std::array<double, 3>& pose, double angle, const std::array<double, 2>& centre,
                          double radius) {
  BeamGeometry g;
  const double a = pose[2] + angle;
  g.d = rayCircleDistance(pose[0], pose[1], a, centre[0], centre[1], radius);
  const double perp = (centre[1] - pose[1]) * std::cos(a) - (centre[0] - pose[0]) * std::sin(a);
  g.lateral = perp / radius;
  g.cos_inc = clampCosIncidence(std::sqrt(std::max(0.0, 1.0 - g.lateral * g.lateral)));
  return g;
}

/// Noise shape h (sigma = scale * h) of a reading: the law's dependence on d and the incidence.
double noiseShape(const NoiseModel& n, const BiasPolynomial& f, double d, double cos_inc, double gamma) {
  double h = 1.0;
  switch (n.kind) {
    case NoiseKind::squared: h = f(d) * f(d); break;
    case NoiseKind::power: h = std::pow(std::abs(f(d)), n.exponent); break;
    case NoiseKind::polynomial: {
      NoiseModel unit = n;
      h = unit.stddev(d, f);
      break;
    }
    default: break;
  }
  return h * incidenceNoiseFactor(gamma, cos_inc);
}

/// Maximises a unimodal function on [lo, hi] by golden-section search.
template <typename F>
double goldenMax(F&& fn, double lo, double hi, int iterations = 40) {
  constexpr double kG = 0.6180339887498949;
  double a = lo, b = hi;
  double c = b - kG * (b - a), d = a + kG * (b - a);
  double fc = fn(c), fd = fn(d);
  for (int i = 0; i < iterations; ++i) {
    if (fc > fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - kG * (b - a);
      fc = fn(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + kG * (b - a);
      fd = fn(d);
    }
  }
  return 0.5 * (a + b);
}

}  // namespace

const char* toString(MotionPrior m) {
  switch (m) {
    case MotionPrior::automatic: return "automatic";
    case MotionPrior::off: return "off";
    case MotionPrior::on: return "on";
  }
  return "unknown";
}

bool continuousMotion(const LandmarkObservations& obs, const JointConfig& config) {
  if (obs.commanded.size() < static_cast<std::size_t>(std::max(config.motion_min_stops, 1))) return false;
  // Distinct scans with sightings per stop (sightings come scan by scan, but do not rely on it).
  std::vector<std::vector<std::size_t>> scans(obs.commanded.size());
  for (const auto& s : obs.sightings)
    if (s.stop < scans.size()) scans[s.stop].push_back(s.scan);
  std::size_t seen = 0, single = 0;
  for (auto& v : scans) {
    if (v.empty()) continue;
    std::sort(v.begin(), v.end());
    ++seen;
    single += v.front() == v.back();
  }
  return seen > 0 && 2 * single > seen;
}

void JointConfig::validate() const {
  if (order < 1 || order > 6) throw std::invalid_argument("JointConfig: order must be 1..6");
  if (noise != NoiseKind::squared && noise != NoiseKind::polynomial && noise != NoiseKind::constant &&
      noise != NoiseKind::power)
    throw std::invalid_argument("JointConfig: noise must be squared, power, polynomial or constant");
  if ((effects.incidence_noise || effects.noise_exponent) && noise == NoiseKind::polynomial)
    throw std::invalid_argument("JointConfig: incidence_noise and noise_exponent need the squared, power or constant law");
  if (!(sigma_s_m > 0.0) || !(sigma_psi_rad > 0.0)) throw std::invalid_argument("JointConfig: priors must be positive");
  if (!(huber_sigmas > 0.0)) throw std::invalid_argument("JointConfig: huber_sigmas must be positive");
  if (!(lateral_fraction > 0.0 && lateral_fraction <= 1.0))
    throw std::invalid_argument("JointConfig: lateral_fraction must be in (0, 1]");
  if (outer_iterations < 1) throw std::invalid_argument("JointConfig: outer_iterations must be >= 1");
  if (!(outlier_floor >= 0.0 && outlier_floor < 1.0)) throw std::invalid_argument("JointConfig: outlier_floor must be in [0, 1)");
  if (!(motion_sigma_fraction >= 0.0) || !(motion_heading_sigma_rad_per_m >= 0.0) || !(motion_sigma_floor_m > 0.0) ||
      !(motion_heading_floor_rad > 0.0) || !std::isfinite(motion_sigma_fraction + motion_heading_sigma_rad_per_m +
                                                          motion_sigma_floor_m + motion_heading_floor_rad))
    throw std::invalid_argument("JointConfig: motion prior sigmas must be finite, fractions >= 0, floors > 0");
}

double readingLogLikelihood(double y, double mean, double sigma, double mixed_fraction, double outlier_floor,
                            double window_min, double window_max) {
  const double z = (y - mean) / sigma;
  const double log_normal = -0.5 * (kLog2Pi + z * z) - std::log(sigma);
  if (mixed_fraction <= 0.0 && outlier_floor <= 0.0) return log_normal;
  // Mixture densities, computed relative to the normal density to stay finite far in the tails.
  double mixed = 0.0;
  if (mixed_fraction > 0.0 && y >= mean && y <= window_max && window_max > mean) mixed = 1.0 / (window_max - mean);
  const double floor_density = window_max > window_min ? 1.0 / (window_max - window_min) : 0.0;
  const double other = mixed_fraction * mixed + outlier_floor * floor_density;
  const double keep = (1.0 - mixed_fraction) * (1.0 - outlier_floor);
  // log(keep * N + other) = log_normal + log(keep + other / N)
  if (other <= 0.0) return std::log(keep) + log_normal;
  const double log_other = std::log(other);
  const double hi = std::max(std::log(keep) + log_normal, log_other);
  return hi + std::log(std::exp(std::log(keep) + log_normal - hi) + std::exp(log_other - hi));
}

JointResult refineJoint(const LandmarkObservations& obs, const JointInit& init, const JointConfig& config) {
  config.validate();
  if (init.poses.size() != obs.commanded.size()) throw std::invalid_argument("refineJoint: one initial pose per stop");
  const JointEffects& fx = config.effects;

  JointResult out;
  out.motion_prior = config.motion == MotionPrior::on ||
                     (config.motion == MotionPrior::automatic && continuousMotion(obs, config));
  const bool motion = out.motion_prior && init.poses.size() >= 2;
  out.model = init.model;
  out.model.bias.alpha.resize(static_cast<std::size_t>(config.order) + 1, 0.0);
  out.model.noise.kind = config.noise;
  if (config.noise == NoiseKind::polynomial && out.model.noise.beta.empty())
    out.model.noise.beta.assign(static_cast<std::size_t>(config.noise_order) + 1, 0.0);
  if (config.noise == NoiseKind::power && init.model.noise.kind != NoiseKind::power) out.model.noise.exponent = 2.0;
  if (fx.noise_exponent && out.model.noise.kind == NoiseKind::squared) {
    out.model.noise.kind = NoiseKind::power;
    out.model.noise.exponent = 2.0;
  }

  // Parameter blocks.
  std::vector<std::array<double, 3>> poses(init.poses.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    poses[k] = {init.poses[k].x_m, init.poses[k].y_m, init.poses[k].yaw_rad};
  }
  std::map<int, std::array<double, 2>> centres;
  for (const auto& [id, c] : init.centres) centres[id] = {c.x(), c.y()};
  double radius = init.radius_m;
  std::vector<double> alpha = out.model.bias.alpha;
  std::map<int, double> offsets;  // landmark offsets; the first landmark is the reference (0)
  for (const auto& [id, c] : centres) offsets[id] = 0.0;
  std::array<double, 3> globals{0.0, 0.0, 0.0};  // drift, zero-angle offset, incidence bias
  double scale = 0.0;                             // odometry scale
  double gamma = 0.0;                             // incidence noise exponent
  double mixed_fraction = fx.mixed_pixels ? 0.05 : 0.0;
  {  // Start the terms that are on from the given estimates.
    const JointEffectEstimates& e0 = init.effects;
    if (fx.landmark_offsets && !offsets.empty() && !e0.landmark_offset_m.empty()) {
      // Internally the first landmark is the reference: its reported offset moves into alpha_0.
      auto first = e0.landmark_offset_m.find(offsets.begin()->first);
      const double ref = first != e0.landmark_offset_m.end() ? first->second : 0.0;
      for (auto& [id, o] : offsets) {
        auto it = e0.landmark_offset_m.find(id);
        o = (it != e0.landmark_offset_m.end() ? it->second : 0.0) - ref;
      }
      alpha[0] += ref;
    }
    if (fx.drift) globals[0] = e0.drift_m_per_scan;
    if (fx.angle_offset) globals[1] = e0.angle_offset_rad;
    if (fx.incidence_bias) globals[2] = e0.incidence_bias_m;
    if (fx.odometry_scale) scale = e0.odometry_scale;
    if (fx.incidence_noise) gamma = e0.incidence_noise_exponent;
    if (fx.mixed_pixels && e0.mixed_pixel_fraction > 0.0) mixed_fraction = e0.mixed_pixel_fraction;
  }

  // Reading window (outlier floor, mixed pixels).
  out.window_min_m = obs.range_min_m;
  out.window_max_m = obs.range_max_m;
  if (!(obs.range_max_m < 1e8)) {
    double m = 0.0;
    for (const auto& s : obs.sightings)
      for (const auto& b : s.beams)
        if (std::isfinite(b.range_m)) m = std::max(m, b.range_m);
    out.window_max_m = 1.25 * std::max(m, 1e-3);
  }
  const double window_max = out.window_max_m;

  // Drift reference: the mean scan index of the readings.
  {
    double sum = 0.0, n = 0.0;
    for (const auto& s : obs.sightings) {
      sum += static_cast<double>(s.scan) * static_cast<double>(s.beams.size());
      n += static_cast<double>(s.beams.size());
    }
    out.effects.drift_reference_scan = n > 0 ? sum / n : 0.0;
  }
  const double t_ref = out.effects.drift_reference_scan;

  // Readings on the central part of each landmark (lateral offset < fraction * radius): beams
  // near the edges have range derivatives that blow up at the tangent. Re-selected from the
  // current estimate before every solve (unless the caller selected them: keep_all_beams).
  std::vector<Reading> readings;
  auto selectReadings = [&]() {
    readings.clear();
    for (const auto& s : obs.sightings) {
      auto it = centres.find(s.landmark);
      if (it == centres.end() || s.stop >= poses.size()) continue;
      const auto& p = poses[s.stop];
      for (std::size_t j = 0; j < s.beams.size(); ++j) {
        const auto& b = s.beams[j];
        if (!std::isfinite(b.range_m)) continue;
        const bool edge = j == 0 || j + 1 == s.beams.size();
        if (config.keep_all_beams) {
          readings.push_back({s.stop, s.scan, s.landmark, b.angle_rad, b.range_m, edge});
          continue;
        }
        const double a = p[2] + b.angle_rad + globals[1];
        const double perp = (it->second[1] - p[1]) * std::cos(a) - (it->second[0] - p[0]) * std::sin(a);
        if (std::abs(perp) < config.lateral_fraction * radius)
          readings.push_back({s.stop, s.scan, s.landmark, b.angle_rad, b.range_m, edge});
      }
    }
  };
  selectReadings();
  if (readings.size() < static_cast<std::size_t>(config.order + 2) * 4) {
    out.message = "too few landmark readings for the joint refinement (" + std::to_string(readings.size()) + ")";
    return out;
  }

  std::vector<BeamGeometry> geo;
  std::vector<double> sigma, weight;  // weight: 1 - mixed-pixel responsibility
  auto currentGeometry = [&]() {
    geo.resize(readings.size());
    for (std::size_t i = 0; i < readings.size(); ++i) {
      const auto& r = readings[i];
      geo[i] = beamGeometry(poses[r.stop], r.angle_rad + globals[1], centres.at(r.landmark), radius);
    }
  };
  auto meanOf = [&](std::size_t i, const BiasPolynomial& f) {
    const auto& r = readings[i];
    double m = f(geo[i].d);
    if (fx.landmark_offsets) m += offsets.at(r.landmark);
    if (fx.drift) m += globals[0] * (static_cast<double>(r.scan) - t_ref);
    if (fx.incidence_bias) m += globals[2] * (1.0 - geo[i].cos_inc);
    return m;
  };
  auto scaleOf = [](const NoiseModel& n) {
    return n.kind == NoiseKind::polynomial ? 1.0 : n.sigma_e;
  };
  auto sigmaOf = [&](std::size_t i, const RangeModel& m) {
    return scaleOf(m.noise) * noiseShape(m.noise, m.bias, geo[i].d, geo[i].cos_inc, gamma);
  };

  // Repeated scans from one pose: the readings of one beam on one landmark at one stop share
  // their geometry, so (Gaussian) sum_i (y_i - f)^2 = n (ybar - f)^2 + sum_i (y_i - ybar)^2, and
  // one residual sqrt(n) (ybar - f) / sigma carries all they say about the parameters: the cost
  // of a solve no longer grows with the scans per stop. Not when a term depends on the scan
  // (drift) or on each reading (mixed-pixel weights). The robust loss acts on the group.
  const bool pool = config.pool_repeated_scans && !fx.drift && !fx.mixed_pixels;
  struct Pooled {
    std::size_t first = 0, n = 0;
    double sum_y = 0.0, sum_angle = 0.0;
  };
  auto addResiduals = [&](ceres::Problem& problem, bool robust) {
    // `count` readings behind one residual: the loss's threshold scales with sqrt(count), so a
    // pooled residual is down-weighted when its mean is off by huber_sigmas standard deviations
    // of one reading, as a single reading would be (not when it is off by that many standard
    // errors of the mean: a millimetre of geometry error would then put every group there).
    auto add = [&](const Reading& r, double angle, double y, double inv, double count) {
      ceres::LossFunction* loss = nullptr;
      const double threshold = config.huber_sigmas * std::sqrt(count);
      if (robust && config.cauchy_loss) loss = new ceres::CauchyLoss(threshold);
      else if (robust) loss = new ceres::HuberLoss(threshold);
      if (fx.anyMean()) {
        problem.AddResidualBlock(effectCost(config.order, angle, y, inv, static_cast<double>(r.scan) - t_ref), loss,
                                 poses[r.stop].data(), centres.at(r.landmark).data(), &radius, alpha.data(),
                                 &offsets.at(r.landmark), globals.data());
      } else {
        problem.AddResidualBlock(beamCost(config.order, angle, y, inv), loss, poses[r.stop].data(),
                                 centres.at(r.landmark).data(), &radius, alpha.data());
      }
    };
    bool pooled = false;
    if (pool) {
      // Key: stop, landmark, beam angle to 1e-5 rad (angles recovered from float coordinates
      // differ by ~1e-7 from scan to scan; beams are 1e-3 rad apart or more). Ordered: the
      // residuals go in in one order whatever the order of the readings.
      std::map<std::tuple<std::size_t, int, long long>, Pooled> groups;
      for (std::size_t i = 0; i < readings.size(); ++i) {
        const auto& r = readings[i];
        Pooled& g = groups[{r.stop, r.landmark, std::llround(r.angle_rad * 1e5)}];
        if (g.n == 0) g.first = i;
        ++g.n;
        g.sum_y += r.y_m;
        g.sum_angle += r.angle_rad;
      }
      pooled = groups.size() < readings.size();  // else every reading is alone (a pose per scan)
      if (pooled) {
        for (const auto& [key, g] : groups) {
          const double n = static_cast<double>(g.n);
          add(readings[g.first], g.sum_angle / n, g.sum_y / n, std::sqrt(n) / sigma[g.first], n);
        }
        out.reading_residuals = groups.size();
      }
    }
    if (!pooled) {
      for (std::size_t i = 0; i < readings.size(); ++i)
        add(readings[i], readings[i].angle_rad, readings[i].y_m, std::sqrt(std::max(weight[i], 1e-6)) / sigma[i], 1.0);
      out.reading_residuals = readings.size();
    }
    const Pose2& c0 = obs.commanded.front();
    for (std::size_t k = 0; k < poses.size(); ++k) {
      const Pose2& c = obs.commanded[k];
      const double yaw = poses[k][2] + wrapAngle(c.yaw_rad - poses[k][2]);  // unwrapped next to the estimate
      if (motion && k > 0) {
        // Continuous motion: the commanded step from the previous stop (the first stop's prior
        // below fixes the gauge).
        const Pose2 step = commandedStep(obs.commanded[k - 1], c);
        const double now = poses[k][2] - poses[k - 1][2];
        const double len = std::hypot(step.x_m, step.y_m);
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<MotionPriorCost, 3, 3, 3, 1>(new MotionPriorCost{
                step.x_m, step.y_m, now + wrapAngle(step.yaw_rad - now),
                1.0 / (config.motion_sigma_fraction * len + config.motion_sigma_floor_m),
                1.0 / (config.motion_heading_sigma_rad_per_m * len + config.motion_heading_floor_rad)}),
            nullptr, poses[k - 1].data(), poses[k].data(), &scale);
        if (!fx.odometry_scale) problem.SetParameterBlockConstant(&scale);
      } else if (fx.odometry_scale) {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ScaledPosePriorCost, 3, 3, 1>(new ScaledPosePriorCost{
                                     c.x_m, c.y_m, yaw, c0.x_m, c0.y_m, 1.0 / config.sigma_s_m, 1.0 / config.sigma_psi_rad}),
                                 nullptr, poses[k].data(), &scale);
      } else {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PosePriorCost, 3, 3>(new PosePriorCost{
                                     c.x_m, c.y_m, yaw, 1.0 / config.sigma_s_m, 1.0 / config.sigma_psi_rad}),
                                 nullptr, poses[k].data());
      }
      if (!fx.estimate_heading && problem.HasParameterBlock(poses[k].data()))
        problem.SetManifold(poses[k].data(), new ceres::SubsetManifold(3, {2}));
    }
    if (fx.anyMean()) {
      // Offsets: the first landmark is the reference (its offset is alpha_0's); others free when on.
      bool first = true;
      for (auto& [id, o] : offsets) {
        if (!problem.HasParameterBlock(&o)) continue;
        if (first || !fx.landmark_offsets) problem.SetParameterBlockConstant(&o);
        first = false;
      }
      std::vector<int> fixed;
      if (!fx.drift) fixed.push_back(0);
      if (!fx.angle_offset) fixed.push_back(1);
      if (!fx.incidence_bias) fixed.push_back(2);
      if (fixed.size() == 3) problem.SetParameterBlockConstant(globals.data());
      else if (!fixed.empty()) problem.SetManifold(globals.data(), new ceres::SubsetManifold(3, fixed));
    }
    if (!config.estimate_radius && problem.HasParameterBlock(&radius)) problem.SetParameterBlockConstant(&radius);
  };

  // Size of the noise law, to tell when its re-estimation has settled.
  auto noiseScale = [&](const NoiseModel& n) {
    if (n.kind == NoiseKind::polynomial) return n.beta.empty() ? 0.0 : std::abs(n.beta.front()) + std::abs(n.beta.back());
    return n.sigma_e;
  };
  double previous_scale = noiseScale(out.model.noise);
  // Mixed pixels (EM): the responsibility of the uniform for each outermost beam; the fit
  // weighs a reading by 1 - responsibility.
  auto responsibilities = [&](const std::vector<double>& res) {
    weight.assign(readings.size(), 1.0);
    if (!fx.mixed_pixels) return;
    for (std::size_t i = 0; i < readings.size(); ++i) {
      if (!readings[i].edge) continue;
      const double mean = readings[i].y_m - res[i];
      const double u = (res[i] >= 0.0 && readings[i].y_m <= window_max && window_max > mean) ? 1.0 / (window_max - mean) : 0.0;
      const double z = res[i] / sigma[i];
      const double nd = std::exp(-0.5 * z * z) / (sigma[i] * std::sqrt(2.0 * kPi));
      weight[i] = 1.0 - mixed_fraction * u / (mixed_fraction * u + (1.0 - mixed_fraction) * nd + 1e-300);
    }
  };
  auto residualsNow = [&](const BiasPolynomial& f) {
    std::vector<double> res(readings.size());
    for (std::size_t i = 0; i < readings.size(); ++i) res[i] = readings[i].y_m - meanOf(i, f);
    return res;
  };
  weight.assign(readings.size(), 1.0);
  // Iteration 0 settles the geometry (poses, centres, radius) with the starting bias held;
  // later iterations free everything and re-estimate the noise law in between.
  for (int outer = config.settle_geometry ? 0 : 1; outer <= config.outer_iterations; ++outer) {
    out.outer_iterations = outer;
    if (outer > 0 && config.reselect && !config.keep_all_beams) selectReadings();
    currentGeometry();
    sigma.resize(readings.size());
    RangeModel current = out.model;
    current.bias.alpha = alpha;
    for (std::size_t i = 0; i < readings.size(); ++i) sigma[i] = std::max(sigmaOf(i, current), 1e-4);
    if (outer > 0) responsibilities(residualsNow(current.bias));  // E-step (weights 1 without mixed pixels)
    else weight.assign(readings.size(), 1.0);

    ceres::Problem::Options problem_options;
    ceres::Problem problem(problem_options);
    addResiduals(problem, true);
    if (!problem.HasParameterBlock(alpha.data())) {
      out.message = "no landmark reading left to fit";
      return out;
    }
    if (config.estimate_radius) problem.SetParameterLowerBound(&radius, 0, 1e-3);
    if (outer == 0) problem.SetParameterBlockConstant(alpha.data());

    ceres::Solver::Options options;
    // Stop and go: the poses are independent of each other and the Schur complement eliminates
    // them (a dense reduced system over the centres and the model). Chained by the motion prior
    // they are not; a sparse Cholesky of the whole normal matrix (SuiteSparse, fill-reducing
    // ordering) keeps time and memory linear in the poses.
    options.linear_solver_type = motion ? ceres::SPARSE_NORMAL_CHOLESKY : ceres::DENSE_SCHUR;
    options.max_num_iterations = config.max_solver_iterations;
    options.function_tolerance = 1e-10;
    options.parameter_tolerance = 1e-10;
    options.num_threads = 1;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    out.solver_iterations += static_cast<int>(summary.iterations.size());
    out.converged = summary.termination_type == ceres::CONVERGENCE;
    if (!summary.IsSolutionUsable()) {
      out.message = "Ceres did not find a usable solution: " + summary.message;
      out.converged = false;
      return out;
    }

    if (outer == 0) continue;
    // Re-estimate the noise law (and the mixed-pixel fraction, M-step) from the readings that
    // are not outliers.
    currentGeometry();
    current.bias.alpha = alpha;
    const std::vector<double> res = residualsNow(current.bias);
    if (fx.mixed_pixels) {
      responsibilities(res);
      double sum = 0.0, n = 0.0;
      for (std::size_t i = 0; i < readings.size(); ++i)
        if (readings[i].edge) {
          sum += 1.0 - weight[i];
          n += 1.0;
        }
      mixed_fraction = n > 0 ? std::clamp(sum / n, 1e-4, 0.9) : 0.0;
    }
    std::vector<std::size_t> in;  // readings used for the noise law
    for (std::size_t i = 0; i < readings.size(); ++i)
      if (std::abs(res[i]) <= 4.0 * sigma[i] && weight[i] > 0.5) in.push_back(i);
    if (config.noise == NoiseKind::polynomial) {
      std::vector<double> din, rin;
      for (std::size_t i : in) {
        din.push_back(geo[i].d);
        rin.push_back(res[i]);
      }
      out.model.noise.beta = fitNoisePolynomial(din, rin, config.noise_order);
    } else if (config.noise != NoiseKind::polynomial) {
      // sigma_i = sigma_e h_i(kappa, gamma): sigma_e profiled out, kappa and gamma by golden section.
      auto profile = [&](NoiseModel n, double g, double* sigma_e) {
        double s2 = 0.0, logh = 0.0;
        for (std::size_t i : in) {
          const double h = std::max(noiseShape(n, current.bias, geo[i].d, geo[i].cos_inc, g), 1e-9);
          s2 += res[i] * res[i] / (h * h);
          logh += std::log(h);
        }
        const double m = static_cast<double>(std::max<std::size_t>(in.size(), 1));
        s2 /= m;
        if (sigma_e) *sigma_e = std::sqrt(s2);
        return -0.5 * m * std::log(std::max(s2, 1e-300)) - logh;  // profile log-likelihood (up to constants)
      };
      for (int pass = 0; pass < 2; ++pass) {
        if (fx.noise_exponent) {
          out.model.noise.exponent = goldenMax(
              [&](double k) {
                NoiseModel n = out.model.noise;
                n.exponent = k;
                return profile(n, gamma, nullptr);
              },
              -1.0, 5.0);
        }
        if (fx.incidence_noise) gamma = goldenMax([&](double g) { return profile(out.model.noise, g, nullptr); }, -1.0, 4.0);
      }
      profile(out.model.noise, gamma, &out.model.noise.sigma_e);
    }
    const double s_now = noiseScale(out.model.noise);
    if (previous_scale > 0.0 && std::abs(s_now - previous_scale) <= 1e-2 * previous_scale) break;
    previous_scale = s_now;
    if (outer == config.outer_iterations) {
      out.converged = false;
      out.message = "noise model still changing after " + std::to_string(config.outer_iterations) + " re-estimations";
    }
  }

  // Landmark offsets are reported with mean zero; their mean goes into alpha_0.
  if (fx.landmark_offsets && !offsets.empty()) {
    double mean = 0.0;
    for (const auto& [id, o] : offsets) mean += o / static_cast<double>(offsets.size());
    for (auto& [id, o] : offsets) o -= mean;
    alpha[0] += mean;
  }
  out.model.bias.alpha = alpha;
  out.radius_m = radius;
  out.poses.resize(poses.size());
  double ps = 0.0, hs = 0.0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    out.poses[k] = Pose2{poses[k][0], poses[k][1], wrapAngle(poses[k][2])};
    ps += std::pow(poses[k][0] - obs.commanded[k].x_m, 2) + std::pow(poses[k][1] - obs.commanded[k].y_m, 2);
    hs += std::pow(wrapAngle(poses[k][2] - obs.commanded[k].yaw_rad), 2);
  }
  out.pose_scatter_m = std::sqrt(ps / (2.0 * static_cast<double>(poses.size())));
  {
    const Pose2& c0 = obs.commanded.front();
    const double s = fx.odometry_scale ? scale : 0.0;
    auto add = [&](double ex, double ey, double sd) {
      out.prior_neg_log_likelihood += 0.5 * (ex * ex + ey * ey) / (sd * sd) + kLog2Pi + 2.0 * std::log(sd);
    };
    for (std::size_t k = 0; k < poses.size(); ++k) {
      if (motion && k > 0) {
        const Pose2 step = commandedStep(obs.commanded[k - 1], obs.commanded[k]);
        const Pose2 est = commandedStep(out.poses[k - 1], out.poses[k]);
        add(est.x_m - (1.0 + s) * step.x_m, est.y_m - (1.0 + s) * step.y_m,
            config.motion_sigma_fraction * std::hypot(step.x_m, step.y_m) + config.motion_sigma_floor_m);
        continue;
      }
      add(poses[k][0] - (c0.x_m + (1.0 + s) * (obs.commanded[k].x_m - c0.x_m)),
          poses[k][1] - (c0.y_m + (1.0 + s) * (obs.commanded[k].y_m - c0.y_m)), config.sigma_s_m);
    }
  }
  out.heading_scatter_rad = std::sqrt(hs / static_cast<double>(poses.size()));
  for (const auto& [id, c] : centres) out.centres[id] = Eigen::Vector2d(c[0], c[1]);

  // Effects.
  JointEffectEstimates& e = out.effects;
  if (fx.landmark_offsets) e.landmark_offset_m = offsets;
  e.drift_m_per_scan = fx.drift ? globals[0] : 0.0;
  e.angle_offset_rad = fx.angle_offset ? globals[1] : 0.0;
  e.incidence_bias_m = fx.incidence_bias ? globals[2] : 0.0;
  e.incidence_noise_exponent = gamma;
  e.noise_exponent = out.model.noise.kind == NoiseKind::power ? out.model.noise.exponent
                     : out.model.noise.kind == NoiseKind::constant ? 0.0
                                                                    : 2.0;
  e.mixed_pixel_fraction = fx.mixed_pixels ? mixed_fraction : 0.0;
  e.odometry_scale = fx.odometry_scale ? scale : 0.0;
  e.heading_rms_rad = out.heading_scatter_rad;
  out.effect_parameters = (fx.landmark_offsets ? static_cast<int>(offsets.size()) - 1 : 0) + (fx.drift ? 1 : 0) +
                          (fx.angle_offset ? 1 : 0) + (fx.incidence_bias ? 1 : 0) + (fx.incidence_noise ? 1 : 0) +
                          (fx.noise_exponent ? 1 : 0) + (fx.mixed_pixels ? 1 : 0) + (fx.odometry_scale ? 1 : 0) +
                          (fx.estimate_heading ? static_cast<int>(poses.size()) : 0);

  // Likelihood at the solution (all readings, with the mixed-pixel and outlier terms) and
  // information criteria.
  currentGeometry();
  out.neg_log_likelihood = 0.0;
  out.outliers = 0;
  out.residual_rms_m = 0.0;
  std::vector<double> d(readings.size());
  for (std::size_t i = 0; i < readings.size(); ++i) {
    d[i] = geo[i].d;
    const double s = std::max(sigmaOf(i, out.model), 1e-6);
    const double mean = meanOf(i, out.model.bias);
    const double r = (readings[i].y_m - mean) / s;
    out.neg_log_likelihood -= readingLogLikelihood(readings[i].y_m, mean, s, readings[i].edge ? e.mixed_pixel_fraction : 0.0,
                                                   config.outlier_floor, out.window_min_m, window_max);
    out.residual_rms_m += r * r * s * s;
    if (std::abs(r) > config.huber_sigmas * 2.0) ++out.outliers;
  }
  out.residual_rms_m = std::sqrt(out.residual_rms_m / static_cast<double>(readings.size()));
  out.readings = readings.size();
  out.distances_m = d;
  out.readings_m.reserve(readings.size());
  for (const auto& r : readings) out.readings_m.push_back(r.y_m);
  const int heading_params = fx.estimate_heading ? static_cast<int>(poses.size()) : 0;
  const double k = static_cast<double>(config.order + 1) +
                   (config.noise == NoiseKind::polynomial ? config.noise_order + 1.0 : 1.0) +
                   (config.estimate_radius ? 1.0 : 0.0) + static_cast<double>(out.effect_parameters - heading_params);
  out.aic = 2.0 * k + 2.0 * out.neg_log_likelihood;
  out.bic = k * std::log(static_cast<double>(readings.size())) + 2.0 * out.neg_log_likelihood;

  // Centre-bearing residuals: detected centre bearing vs the refined geometry.
  double bs = 0.0;
  std::size_t bn = 0;
  for (const auto& s : obs.sightings) {
    auto it = out.centres.find(s.landmark);
    if (it == out.centres.end() || s.stop >= out.poses.size()) continue;
    const Pose2& p = out.poses[s.stop];
    const double predicted = std::atan2(it->second.y() - p.y_m, it->second.x() - p.x_m) - p.yaw_rad - e.angle_offset_rad;
    bs += std::pow(wrapAngle(s.bearing_rad - predicted), 2);
    ++bn;
  }
  out.sigma_theta_rad = bn ? std::sqrt(bs / static_cast<double>(bn)) : 0.0;

  if (config.covariance) {
    // Covariance of alpha and the centres with the final weights; the pose priors fix the gauge.
    for (std::size_t i = 0; i < readings.size(); ++i) sigma[i] = std::max(sigmaOf(i, out.model), 1e-4);
    ceres::Problem problem;
    addResiduals(problem, false);
    ceres::Covariance::Options copt;
    // A dense SVD of the whole Jacobian (rank-revealing: a pseudo-inverse where the data leave a
    // direction free) costs readings x parameters memory: over 20 GB for a 4791-pose CARMEN
    // log. Beyond a few hundred poses the sparse QR computes the same blocks (the pose priors
    // make the Jacobian full rank) in memory that grows with the poses.
    if (problem.NumParameters() <= config.dense_covariance_max_parameters) {
      copt.algorithm_type = ceres::DENSE_SVD;
      copt.null_space_rank = -1;
    } else {
      copt.algorithm_type = ceres::SPARSE_QR;
    }
    auto cov = std::make_unique<ceres::Covariance>(copt);
    std::vector<std::pair<const double*, const double*>> blocks = {{alpha.data(), alpha.data()}};
    const bool radius_free = config.estimate_radius && problem.HasParameterBlock(&radius);
    if (radius_free) {
      blocks.emplace_back(alpha.data(), &radius);
      blocks.emplace_back(&radius, &radius);
    }
    for (auto& [id, c] : centres)
      if (problem.HasParameterBlock(c.data())) blocks.emplace_back(c.data(), c.data());
    bool computed = problem.HasParameterBlock(alpha.data()) && cov->Compute(blocks, &problem);
    if (!computed && problem.HasParameterBlock(alpha.data()) && copt.algorithm_type == ceres::SPARSE_QR) {
      // The sparse QR needs full rank; a landmark whose few beams leave its centre free along a
      // direction (seen once, edge-on: Freiburg 079) makes it fail where the dense SVD would
      // take a pseudo-inverse. Tie every centre to its estimate with 100 m standard deviation:
      // that removes the null space and changes the determined blocks by about (sigma/100 m)^2.
      for (auto& [id, c] : centres)
        if (problem.HasParameterBlock(c.data()))
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<WeakPointPriorCost, 2, 2>(
                                       new WeakPointPriorCost{c[0], c[1], kWeakCentrePriorSigmaM}),
                                   nullptr, c.data());
      cov = std::make_unique<ceres::Covariance>(copt);
      computed = cov->Compute(blocks, &problem);
    }
    if (computed) {
      const int n = config.order + 1;
      out.alpha_covariance.resize(n, n);
      cov->GetCovarianceBlock(alpha.data(), alpha.data(), out.alpha_covariance.data());
      if (radius_free) {
        out.alpha_radius_covariance.resize(n);
        cov->GetCovarianceBlock(alpha.data(), &radius, out.alpha_radius_covariance.data());
        cov->GetCovarianceBlock(&radius, &radius, &out.radius_variance);
      }
      for (auto& [id, c] : centres) {
        if (!problem.HasParameterBlock(c.data())) continue;
        Eigen::Matrix2d m;
        cov->GetCovarianceBlock(c.data(), c.data(), m.data());
        out.centre_covariance[id] = m;
      }
    }
  }
  return out;
}

std::vector<JointReading> evaluateJoint(const LandmarkObservations& obs, const JointResult& fit, const JointConfig& config) {
  std::vector<JointReading> out;
  const JointEffectEstimates& e = fit.effects;
  const double gamma = e.incidence_noise_exponent;
  for (std::size_t si = 0; si < obs.sightings.size(); ++si) {
    const Sighting& s = obs.sightings[si];
    auto c = fit.centres.find(s.landmark);
    if (c == fit.centres.end() || s.stop >= fit.poses.size()) continue;
    const Pose2& p = fit.poses[s.stop];
    const std::array<double, 3> pose{p.x_m, p.y_m, p.yaw_rad};
    const std::array<double, 2> centre{c->second.x(), c->second.y()};
    auto offset = e.landmark_offset_m.find(s.landmark);
    for (std::size_t j = 0; j < s.beams.size(); ++j) {
      const BeamReading& b = s.beams[j];
      if (!std::isfinite(b.range_m)) continue;
      const BeamGeometry g = beamGeometry(pose, b.angle_rad + e.angle_offset_rad, centre, fit.radius_m);
      JointReading r;
      r.sighting = si;
      r.stop = s.stop;
      r.scan = s.scan;
      r.landmark = s.landmark;
      r.beam = b.beam;
      r.angle_rad = b.angle_rad;
      r.y_m = b.range_m;
      r.d_m = g.d;
      r.lateral = g.lateral;
      r.cos_incidence = g.cos_inc;
      r.edge = j == 0 || j + 1 == s.beams.size();
      r.mean_m = fit.model.bias(g.d) + (offset != e.landmark_offset_m.end() ? offset->second : 0.0) +
                 e.drift_m_per_scan * (static_cast<double>(s.scan) - e.drift_reference_scan) +
                 e.incidence_bias_m * (1.0 - g.cos_inc);
      const double scale = fit.model.noise.kind == NoiseKind::polynomial ? 1.0 : fit.model.noise.sigma_e;
      r.sigma_m = std::max(scale * noiseShape(fit.model.noise, fit.model.bias, g.d, g.cos_inc, gamma), 1e-6);
      r.log_likelihood = readingLogLikelihood(r.y_m, r.mean_m, r.sigma_m, r.edge ? e.mixed_pixel_fraction : 0.0,
                                              config.outlier_floor, fit.window_min_m, fit.window_max_m);
      out.push_back(r);
    }
  }
  return out;
}

}  // namespace lidarcal::calibration
