// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/joint_refinement.hpp"

#include <boost/math/distributions/students_t.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <tuple>

#include <ceres/ceres.h>

#include "calibration/joint_problem.hpp"
#include "common/range_effects.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {
const char* toString(MotionPrior m) {
  switch (m) {
    case MotionPrior::automatic:
      return "automatic";
    case MotionPrior::off:
      return "off";
    case MotionPrior::on:
      return "on";
  }
  return "unknown";
}

double KnownRange::count() const {
  double n = 0.0;
  for (const Beam& b : beams) n += b.count;
  return n;
}

double KnownRange::meanDistance(double radius_m) const {
  double sum = 0.0, n = 0.0;
  for (const Beam& b : beams) {
    sum += b.count * distance(b, radius_m);
    n += b.count;
  }
  return n > 0.0 ? sum / n : 0.0;
}

double motionStepLength(const std::vector<Pose2>& commanded, std::size_t k) {
  constexpr std::size_t kHalfWindow = 10;
  const std::size_t first = k > kHalfWindow ? k - kHalfWindow : 1,
                    last = std::min(k + kHalfWindow, commanded.size() - 1);
  const auto lengthOf = [&commanded](std::size_t j) {
    const Pose2 step = stepBetween(commanded[j - 1], commanded[j]);
    return std::hypot(step.x_m, step.y_m);
  };
  std::vector<double> len;
  len.reserve(2 * kHalfWindow);
  for (std::size_t j = first; j <= last; ++j)
    if (j != k) len.push_back(lengthOf(j));
  const double own = lengthOf(k);
  if (len.empty()) return own;
  const double neighbours = median(std::move(len));
  return own >= 0.5 * neighbours && own <= 1.5 * neighbours ? neighbours : own;
}

bool continuousMotion(const LandmarkObservations& obs, const JointConfig& config) {
  if (obs.commanded.size() < static_cast<std::size_t>(std::max(config.motion_min_stops, 1)))
    return false;
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
  if (noise != NoiseKind::squared && noise != NoiseKind::polynomial &&
      noise != NoiseKind::constant && noise != NoiseKind::power)
    throw std::invalid_argument(
        "JointConfig: noise must be squared, power, polynomial or constant");
  if ((effects.incidence_noise || effects.noise_exponent || effects.dark_noise) &&
      noise == NoiseKind::polynomial)
    throw std::invalid_argument(
        "JointConfig: incidence_noise, noise_exponent and dark_noise need the squared, power or "
        "constant law");
  if (!(sigma_s_m > 0.0) || !(sigma_psi_rad > 0.0))
    throw std::invalid_argument("JointConfig: priors must be positive");
  if (!(huber_sigmas > 0.0))
    throw std::invalid_argument("JointConfig: huber_sigmas must be positive");
  if (!(lateral_fraction > 0.0 && lateral_fraction <= 1.0))
    throw std::invalid_argument("JointConfig: lateral_fraction must be in (0, 1]");
  if (outer_iterations < 1)
    throw std::invalid_argument("JointConfig: outer_iterations must be >= 1");
  if (!(outlier_floor >= 0.0 && outlier_floor < 1.0))
    throw std::invalid_argument("JointConfig: outlier_floor must be in [0, 1)");
  if (!(motion_sigma_fraction >= 0.0) || !(motion_heading_sigma_rad_per_m >= 0.0) ||
      !(motion_sigma_floor_m > 0.0) || !(motion_heading_floor_rad > 0.0) ||
      !std::isfinite(motion_sigma_fraction + motion_heading_sigma_rad_per_m + motion_sigma_floor_m +
                     motion_heading_floor_rad))
    throw std::invalid_argument(
        "JointConfig: motion prior sigmas must be finite, fractions >= 0, floors > 0");
  for (const auto& [id, c] : known_centres)
    if (!c.allFinite())
      throw std::invalid_argument("JointConfig: known centre of landmark " + std::to_string(id) +
                                  " not finite");
  for (const auto& [k, p] : known_poses)
    if (!std::isfinite(p.x_m + p.y_m + p.yaw_rad))
      throw std::invalid_argument("JointConfig: known pose of stop " + std::to_string(k) +
                                  " not finite");
}

double studentLogDensity(double x, double sigma, double nu) {
  const double s = sigma * std::sqrt((nu - 2.0) / nu), u = x / s;
  return std::lgamma(0.5 * (nu + 1.0)) - std::lgamma(0.5 * nu) - 0.5 * std::log(nu * kPi) -
         std::log(s) - 0.5 * (nu + 1.0) * std::log1p(u * u / nu);
}

namespace {
/// Probability that a Student t (nu > 2 degrees of freedom, mean mu, standard deviation s)
/// falls in [lo, hi], computed on the side of the tail it lies in (as normalMass).
double studentMass(double lo, double hi, double mu, double s, double nu) {
  const boost::math::students_t t(nu);
  const double scale = s * std::sqrt((nu - 2.0) / nu), a = (lo - mu) / scale, b = (hi - mu) / scale;
  if (a > 0.0)
    return boost::math::cdf(boost::math::complement(t, a)) -
           boost::math::cdf(boost::math::complement(t, b));
  if (b < 0.0) return boost::math::cdf(t, b) - boost::math::cdf(t, a);
  return 1.0 - boost::math::cdf(boost::math::complement(t, b)) - boost::math::cdf(t, a);
}
}  // namespace

double coreLogDensity(double y, double mean, double sigma, double student_dof, double grid_m) {
  if (grid_m > 0.0) {
    const double lo = y - 0.5 * grid_m, hi = y + 0.5 * grid_m;
    const double mass = student_dof > 2.0 ? studentMass(lo, hi, mean, sigma, student_dof)
                                          : normalMass(lo, hi, mean, sigma);
    return std::log(std::max(mass, 1e-300) / grid_m);
  }
  if (student_dof > 2.0) return studentLogDensity(y - mean, sigma, student_dof);
  const double z = (y - mean) / sigma;
  return -0.5 * (kLog2Pi + z * z) - std::log(sigma);
}

double readingLogLikelihood(double y, double mean, double sigma, const ReadingLaw& law) {
  const double mixed_fraction = law.mixed_fraction, outlier_floor = law.outlier_floor;
  const double window_min = law.window_min_m, window_max = law.window_max_m;
  // The core density (named log_normal all the same below).
  const double log_normal = coreLogDensity(y, mean, sigma, law.student_dof, law.grid_m);
  if (mixed_fraction <= 0.0 && outlier_floor <= 0.0) return log_normal;
  // Mixture densities, computed relative to the normal density to stay finite far in the tails.
  double mixed = 0.0;
  if (mixed_fraction > 0.0 && y >= mean && y <= window_max && window_max > mean)
    mixed = 1.0 / (window_max - mean);
  const double floor_density = window_max > window_min ? 1.0 / (window_max - window_min) : 0.0;
  const double other = mixed_fraction * mixed + outlier_floor * floor_density;
  const double keep = (1.0 - mixed_fraction) * (1.0 - outlier_floor);
  // log(keep * N + other) = log_normal + log(keep + other / N)
  if (other <= 0.0) return std::log(keep) + log_normal;
  const double log_other = std::log(other);
  const double hi = std::max(std::log(keep) + log_normal, log_other);
  return hi + std::log(std::exp(std::log(keep) + log_normal - hi) + std::exp(log_other - hi));
}

bool JointEffects::enable(Effect e) {
  switch (e) {
    case Effect::incidence_noise:
      incidence_noise = true;
      return true;
    case Effect::incidence_bias:
      incidence_bias = true;
      return true;
    case Effect::landmark_bias:
      landmark_offsets = true;
      return true;
    case Effect::heading_error:
      estimate_heading = true;
      return true;
    case Effect::range_drift:
      drift = true;
      return true;
    case Effect::mixed_pixels:
      mixed_pixels = true;
      return true;
    case Effect::angle_offset:
      angle_offset = true;
      return true;
    case Effect::range_noise_law:
      noise_exponent = true;
      return true;
    case Effect::odometry_scale:
      odometry_scale = true;
      return true;
    case Effect::heavy_tails:
      student_noise = true;
      return true;
    case Effect::quantisation:
      quantised = true;
      return true;
    case Effect::dark_surface:
      dark_noise = true;
      return true;
  }
  return false;
}

JointResult refineJoint(const LandmarkObservations& obs, const JointInit& init,
                        const JointConfig& config) {
  return joint::JointProblem(obs, init, config).run();
}

JointInit initFrom(const JointResult& r) {
  JointInit i;
  i.poses = r.poses;
  i.centres = r.centres;
  i.radius_m = r.radius_m;
  i.model = r.model;
  i.effects = r.effects;
  return i;
}

std::vector<JointReading> evaluateJoint(const LandmarkObservations& obs, const JointResult& fit,
                                        const JointConfig& config) {
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
      const joint::BeamGeometry g = joint::beamGeometry(
          pose.data(), b.angle_rad + e.angle_offset_rad, centre.data(), fit.radius_m);
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
      r.darkness = darkness(b.intensity, e.dark_reference_intensity);
      r.edge = j == 0 || j + 1 == s.beams.size();
      r.mean_m = expectedReading(
          fit.model.bias(g.d), offset != e.landmark_offset_m.end() ? offset->second : 0.0,
          e.drift_m_per_scan, static_cast<double>(s.scan) - e.drift_reference_scan,
          e.incidence_bias_m, g.cos_inc);
      r.sigma_m =
          std::max(joint::readingSigma(fit.model.noise, fit.model.bias,
                                       {g.d, g.cos_inc, gamma, r.darkness, e.dark_noise_exponent}),
                   1e-6);
      r.log_likelihood = readingLogLikelihood(
          r.y_m, r.mean_m, r.sigma_m,
          ReadingLaw{r.edge ? e.mixed_pixel_fraction : 0.0, config.outlier_floor, fit.window_min_m,
                     fit.window_max_m, e.student_dof, e.range_grid_m});
      out.push_back(r);
    }
  }
  return out;
}

}  // namespace lidarcal::calibration
