#include "calibration/joint_problem.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>

#include "calibration/range_model_fit.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration::joint {
namespace {

constexpr double kWeakCentrePriorSigmaM = 100.0;

/// Size of a noise law, to tell when its re-estimation has settled.
double noiseSize(const NoiseModel& n) {
  if (n.kind == NoiseKind::polynomial) return n.beta.empty() ? 0.0 : std::abs(n.beta.front()) + std::abs(n.beta.back());
  return n.sigma_e;
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

/// Ceres options of one solve. Stop and go: the poses are independent of each other and the
/// Schur complement eliminates them (a dense reduced system over the centres and the model).
/// Chained by the motion prior they are not; a sparse Cholesky of the whole normal matrix
/// (SuiteSparse, fill-reducing ordering) keeps time and memory linear in the poses.
ceres::Solver::Options solverOptions(bool motion, int max_iterations) {
  ceres::Solver::Options options;
  options.linear_solver_type = motion ? ceres::SPARSE_NORMAL_CHOLESKY : ceres::DENSE_SCHUR;
  options.max_num_iterations = max_iterations;
  options.function_tolerance = 1e-10;
  options.parameter_tolerance = 1e-10;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  return options;
}

template <int N>
ceres::CostFunction* makeBeamCost(double angle, double y, double inv_sigma) {
  return new BeamRangeAnalyticCost<N>(angle, y, inv_sigma);
}

template <int N>
ceres::CostFunction* makeKnownRangeCost(const KnownRange& k, double inv_sigma) {
  return new ceres::AutoDiffCostFunction<KnownRangeCost<N>, 1, N, 1>(new KnownRangeCost<N>{&k, inv_sigma});
}

template <int N>
ceres::CostFunction* makeEffectCost(double angle, double y, double inv_sigma, double t_rel) {
  return new ceres::AutoDiffCostFunction<EffectBeamCost<N>, 1, 3, 2, 1, N, 1, 3>(
      new EffectBeamCost<N>{angle, y, inv_sigma, t_rel});
}

}  // namespace

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

ceres::CostFunction* knownRangeCost(int order, const KnownRange& k, double inv_sigma) {
  switch (order + 1) {
    case 2: return makeKnownRangeCost<2>(k, inv_sigma);
    case 3: return makeKnownRangeCost<3>(k, inv_sigma);
    case 4: return makeKnownRangeCost<4>(k, inv_sigma);
    case 5: return makeKnownRangeCost<5>(k, inv_sigma);
    case 6: return makeKnownRangeCost<6>(k, inv_sigma);
    case 7: return makeKnownRangeCost<7>(k, inv_sigma);
    default: throw std::invalid_argument("refineJoint: order must be 1..6");
  }
}

BeamGeometry beamGeometry(const double* pose, double angle, const double* centre, double radius) {
  BeamGeometry g;
  const double a = pose[2] + angle;
  g.d = rayCircleDistance(pose[0], pose[1], a, centre[0], centre[1], radius);
  const double perp = (centre[1] - pose[1]) * std::cos(a) - (centre[0] - pose[0]) * std::sin(a);
  g.lateral = perp / radius;
  g.cos_inc = clampCosIncidence(std::sqrt(std::max(0.0, 1.0 - g.lateral * g.lateral)));
  return g;
}

double noiseShape(const NoiseModel& n, const BiasPolynomial& f, double d, double cos_inc, double gamma, double dark,
                  double delta) {
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
  return h * incidenceNoiseFactor(gamma, cos_inc) * darkNoiseFactor(delta, dark);
}

// ---------------------------------------------------------------------------------------------
// Initialisation

JointProblem::JointProblem(const LandmarkObservations& obs, const JointInit& init, const JointConfig& config)
    : obs_(obs), init_(init), config_(config), fx_(config.effects) {
  config.validate();
  if (init.poses.size() != obs.commanded.size()) throw std::invalid_argument("refineJoint: one initial pose per stop");
  out_.motion_prior = config.motion == MotionPrior::on ||
                      (config.motion == MotionPrior::automatic && continuousMotion(obs, config));
  motion_ = out_.motion_prior && init.poses.size() >= 2;
  initialiseModel();
  initialiseParameters();
  startEffectTerms();
  initialiseReadingWindow();
  initialiseDriftReference();
  initialiseReferenceIntensity();
  // Repeated scans from one pose: the readings of one beam on one landmark at one stop share
  // their geometry, so (Gaussian) sum_i (y_i - f)^2 = n (ybar - f)^2 + sum_i (y_i - ybar)^2, and
  // one residual sqrt(n) (ybar - f) / sigma carries all they say about the parameters: the cost
  // of a solve no longer grows with the scans per stop. Not when a term depends on the scan
  // (drift) or on each reading (mixed-pixel weights, a Student t's weights). The robust loss acts
  // on the group. With the dark-surface term a group also shares its intensity.
  pool_ = config.pool_repeated_scans && !fx_.drift && !fx_.mixed_pixels && !fx_.student_noise;
}

void JointProblem::initialiseModel() {
  out_.model = init_.model;
  out_.model.bias.alpha.resize(static_cast<std::size_t>(config_.order) + 1, 0.0);
  out_.model.noise.kind = config_.noise;
  if (config_.noise == NoiseKind::polynomial && out_.model.noise.beta.empty())
    out_.model.noise.beta.assign(static_cast<std::size_t>(config_.noise_order) + 1, 0.0);
  if (config_.noise == NoiseKind::power && init_.model.noise.kind != NoiseKind::power) out_.model.noise.exponent = 2.0;
  if (fx_.noise_exponent && out_.model.noise.kind == NoiseKind::squared) {
    out_.model.noise.kind = NoiseKind::power;
    // Held, the start's exponent is the law; fitted, the first solve weighs by the squared law.
    const bool held = config_.hold_noise_shape && init_.model.noise.kind == NoiseKind::power;
    out_.model.noise.exponent = held ? init_.model.noise.exponent : 2.0;
  }
}

void JointProblem::initialiseParameters() {
  const std::vector<double>& alpha = out_.model.bias.alpha;
  const std::size_t n_poses = init_.poses.size(), n_landmarks = init_.centres.size();
  params_.assign(3 * n_poses + 3 * n_landmarks + alpha.size() + 5, 0.0);
  double* next = params_.data();
  auto take = [&next](std::size_t n) {
    double* block = next;
    next += n;
    return block;
  };
  for (std::size_t k = 0; k < n_poses; ++k) {
    // A measured pose replaces the start and is held there (fixInactiveTerms).
    const auto known = config_.known_poses.find(k);
    const Pose2& p = known != config_.known_poses.end() ? known->second : init_.poses[k];
    poses_.push_back(take(3));
    poses_.back()[0] = p.x_m;
    poses_.back()[1] = p.y_m;
    poses_.back()[2] = p.yaw_rad;
  }
  for (const auto& [id, start] : init_.centres) {
    const auto known = config_.known_centres.find(id);
    const Eigen::Vector2d& c = known != config_.known_centres.end() ? known->second : start;
    double* block = centres_[id] = take(2);
    block[0] = c.x();
    block[1] = c.y();
  }
  n_alpha_ = alpha.size();
  alpha_ = take(n_alpha_);
  std::copy(alpha.begin(), alpha.end(), alpha_);
  for (const auto& [id, c] : init_.centres) offsets_[id] = take(1);
  radius_ = take(1);
  *radius_ = init_.radius_m;
  globals_ = take(3);
  scale_ = take(1);
  mixed_fraction_ = fx_.mixed_pixels ? 0.05 : 0.0;
  dof_ = fx_.student_noise ? 10.0 : 0.0;
}

/// The terms that are on start from the given estimates.
void JointProblem::startEffectTerms() {
  const JointEffectEstimates& e0 = init_.effects;
  if (fx_.landmark_offsets && !offsets_.empty() && !e0.landmark_offset_m.empty()) {
    // Internally the first landmark is the reference: its reported offset moves into alpha_0.
    auto first = e0.landmark_offset_m.find(offsets_.begin()->first);
    const double ref = first != e0.landmark_offset_m.end() ? first->second : 0.0;
    for (auto& [id, o] : offsets_) {
      auto it = e0.landmark_offset_m.find(id);
      *o = (it != e0.landmark_offset_m.end() ? it->second : 0.0) - ref;
    }
    alpha_[0] += ref;
  }
  if (fx_.drift) globals_[0] = e0.drift_m_per_scan;
  if (fx_.angle_offset) globals_[1] = e0.angle_offset_rad;
  if (fx_.incidence_bias) globals_[2] = e0.incidence_bias_m;
  if (fx_.odometry_scale) *scale_ = e0.odometry_scale;
  if (fx_.incidence_noise) gamma_ = e0.incidence_noise_exponent;
  if (fx_.dark_noise) delta_ = e0.dark_noise_exponent;
  if (fx_.mixed_pixels && e0.mixed_pixel_fraction > 0.0) mixed_fraction_ = e0.mixed_pixel_fraction;
  if (fx_.student_noise && e0.student_dof > 2.0) dof_ = e0.student_dof;
}

/// The window of the outlier floor and the mixed pixels: the sensor's, or 1.25 x the largest reading.
void JointProblem::initialiseReadingWindow() {
  out_.window_min_m = obs_.range_min_m;
  out_.window_max_m = obs_.range_max_m;
  if (!(obs_.range_max_m < 1e8)) {
    double m = 0.0;
    for (const auto& s : obs_.sightings)
      for (const auto& b : s.beams)
        if (std::isfinite(b.range_m)) m = std::max(m, b.range_m);
    out_.window_max_m = 1.25 * std::max(m, 1e-3);
  }
  window_max_ = out_.window_max_m;
}

/// Drift reference: the mean scan index of the readings.
void JointProblem::initialiseDriftReference() {
  double sum = 0.0, n = 0.0;
  for (const auto& s : obs_.sightings) {
    sum += static_cast<double>(s.scan) * static_cast<double>(s.beams.size());
    n += static_cast<double>(s.beams.size());
  }
  out_.effects.drift_reference_scan = n > 0 ? sum / n : 0.0;
  t_ref_ = out_.effects.drift_reference_scan;
}

/// I_ref of the dark-surface noise: the start's, else the median intensity of the readings (0:
/// none recorded; every reading's darkness is then 0).
void JointProblem::initialiseReferenceIntensity() {
  reference_intensity_ = init_.effects.dark_reference_intensity;
  if (reference_intensity_ > 0.0) return;
  std::vector<double> v;
  for (const auto& s : obs_.sightings)
    for (const auto& b : s.beams)
      if (std::isfinite(b.range_m) && b.hasIntensity()) v.push_back(b.intensity);
  reference_intensity_ = v.empty() ? 0.0 : median(v);
}

/// Readings on the central part of each landmark (lateral offset < fraction * radius): beams
/// near the edges have range derivatives that blow up at the tangent. Re-selected from the
/// current estimate before every solve (unless the caller selected them: keep_all_beams).
void JointProblem::selectReadings() {
  readings_.clear();
  for (const auto& s : obs_.sightings) {
    auto it = centres_.find(s.landmark);
    if (it == centres_.end() || s.stop >= poses_.size()) continue;
    const auto& p = poses_[s.stop];
    for (std::size_t j = 0; j < s.beams.size(); ++j) {
      const auto& b = s.beams[j];
      if (!std::isfinite(b.range_m)) continue;
      const bool edge = j == 0 || j + 1 == s.beams.size();
      if (config_.keep_all_beams) {
        readings_.push_back({s.stop, s.scan, s.landmark, b.angle_rad, b.range_m, edge,
                             darkness(b.intensity, reference_intensity_)});
        continue;
      }
      const double a = p[2] + b.angle_rad + globals_[1];
      const double perp = (it->second[1] - p[1]) * std::cos(a) - (it->second[0] - p[0]) * std::sin(a);
      if (std::abs(perp) < config_.lateral_fraction * *radius_)
        readings_.push_back({s.stop, s.scan, s.landmark, b.angle_rad, b.range_m, edge,
                             darkness(b.intensity, reference_intensity_)});
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Per reading at the current estimate

void JointProblem::updateGeometry() {
  geo_.resize(readings_.size());
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    const auto& r = readings_[i];
    geo_[i] = beamGeometry(poses_[r.stop], r.angle_rad + globals_[1], centres_.at(r.landmark), *radius_);
  }
}

/// The terms that are off hold their neutral values (zero), so the full expression serves every case.
double JointProblem::meanOf(std::size_t i, const BiasPolynomial& f) const {
  const auto& r = readings_[i];
  return expectedReading(f(geo_[i].d), *offsets_.at(r.landmark), globals_[0], static_cast<double>(r.scan) - t_ref_,
                         globals_[2], geo_[i].cos_inc);
}

double JointProblem::sigmaOf(std::size_t i, const RangeModel& m) const {
  return readingSigma(m.noise, m.bias, geo_[i].d, geo_[i].cos_inc, gamma_, readings_[i].darkness, delta_);
}

std::vector<double> JointProblem::residualsNow(const BiasPolynomial& f) const {
  std::vector<double> res(readings_.size());
  for (std::size_t i = 0; i < readings_.size(); ++i) res[i] = readings_[i].y_m - meanOf(i, f);
  return res;
}

/// Mixed pixels (EM): the responsibility of the uniform for each outermost beam; the fit weighs
/// a reading by 1 - responsibility. Student-t noise (EM for the t as a scale mixture of
/// Gaussians): a reading of residual r weighs (nu + 1) / (nu + (r / s)^2), s = sigma sqrt((nu - 2)
/// / nu) the t's scale; the residual is r / s, so the weight carries nu / (nu - 2) too.
void JointProblem::updateResponsibilities(const std::vector<double>& res) {
  weight_.assign(readings_.size(), 1.0);
  if (fx_.student_noise && dof_ > 2.0) {
    const double to_scale = dof_ / (dof_ - 2.0);
    for (std::size_t i = 0; i < readings_.size(); ++i) {
      const double u2 = res[i] * res[i] / (sigma_[i] * sigma_[i]) * to_scale;
      weight_[i] = (dof_ + 1.0) / (dof_ + u2) * to_scale;
    }
  }
  if (!fx_.mixed_pixels) return;
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    if (!readings_[i].edge) continue;
    const double mean = readings_[i].y_m - res[i];
    const double u =
        (res[i] >= 0.0 && readings_[i].y_m <= window_max_ && window_max_ > mean) ? 1.0 / (window_max_ - mean) : 0.0;
    const double z = res[i] / sigma_[i];
    const double nd = std::exp(-0.5 * z * z) / (sigma_[i] * std::sqrt(2.0 * kPi));
    weight_[i] = 1.0 - mixed_fraction_ * u / (mixed_fraction_ * u + (1.0 - mixed_fraction_) * nd + 1e-300);
  }
}

// ---------------------------------------------------------------------------------------------
// Residuals

void JointProblem::addResiduals(ceres::Problem& problem, bool robust) {
  const bool pooled = pool_ && addPooledReadings(problem, robust);
  if (!pooled) {
    for (std::size_t i = 0; i < readings_.size(); ++i)
      addReading(problem, robust, readings_[i], readings_[i].angle_rad, readings_[i].y_m,
                 std::sqrt(std::max(weight_[i], 1e-6)) / sigma_[i], 1.0);
    out_.reading_residuals = readings_.size();
  }
  addKnownRanges(problem, robust);
  addPosePriors(problem);
  if (fx_.anyMean()) fixInactiveTerms(problem);
  fixKnownGeometry(problem);
  if (!config_.estimate_radius && problem.HasParameterBlock(radius_)) problem.SetParameterBlockConstant(radius_);
}

/// `count` readings behind one residual: the loss's threshold scales with sqrt(count), so a
/// pooled residual is down-weighted when its mean is off by huber_sigmas standard deviations of
/// one reading, as a single reading would be (not when it is off by that many standard errors of
/// the mean: a millimetre of geometry error would then put every group there).
void JointProblem::addReading(ceres::Problem& problem, bool robust, const Reading& r, double angle, double y,
                              double inv, double count) {
  ceres::LossFunction* loss = nullptr;
  const double threshold = config_.huber_sigmas * std::sqrt(count);
  if (robust && config_.cauchy_loss) loss = new ceres::CauchyLoss(threshold);
  else if (robust) loss = new ceres::HuberLoss(threshold);
  if (fx_.anyMean()) {
    problem.AddResidualBlock(effectCost(config_.order, angle, y, inv, static_cast<double>(r.scan) - t_ref_), loss,
                             poses_[r.stop], centres_.at(r.landmark), radius_, alpha_,
                             offsets_.at(r.landmark), globals_);
  } else {
    problem.AddResidualBlock(beamCost(config_.order, angle, y, inv), loss, poses_[r.stop],
                             centres_.at(r.landmark), radius_, alpha_);
  }
}

/// One residual per stop, landmark and beam (the repeated scans' count and mean). False, adding
/// nothing, when every reading is alone (a pose per scan).
bool JointProblem::addPooledReadings(ceres::Problem& problem, bool robust) {
  struct Pooled {
    std::size_t first = 0, n = 0;
    double sum_y = 0.0, sum_angle = 0.0;
  };
  // Key: stop, landmark, beam angle to 1e-5 rad (angles recovered from float coordinates differ
  // by ~1e-7 from scan to scan; beams are 1e-3 rad apart or more), and with the dark-surface
  // term the darkness (readings of one sigma only; with it off the key's last part is 0, so the
  // groups are those of the fit without the term). Ordered: the residuals go in in one order
  // whatever the order of the readings.
  std::map<std::tuple<std::size_t, int, long long, long long>, Pooled> groups;
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    const auto& r = readings_[i];
    const long long dark = fx_.dark_noise ? std::llround(r.darkness * 1e6) : 0;
    Pooled& g = groups[{r.stop, r.landmark, std::llround(r.angle_rad * 1e5), dark}];
    if (g.n == 0) g.first = i;
    ++g.n;
    g.sum_y += r.y_m;
    g.sum_angle += r.angle_rad;
  }
  if (groups.size() >= readings_.size()) return false;
  for (const auto& [key, g] : groups) {
    const double n = static_cast<double>(g.n);
    addReading(problem, robust, readings_[g.first], g.sum_angle / n, g.sum_y / n, std::sqrt(n) / sigma_[g.first], n);
  }
  out_.reading_residuals = groups.size();
  return true;
}

/// The measured targets (JointConfig::known_ranges, seed 004 section 5 beside the self-calibration):
/// the standard error of a target's mean reading is the readings' sigma(d) / sqrt(n) and its tape
/// error carried through the slope, f'(d) tape_sigma, both at the current estimate.
void JointProblem::addKnownRanges(ceres::Problem& problem, bool robust) {
  RangeModel current = out_.model;
  current.bias.alpha = alphaVector();
  for (const KnownRange& k : config_.known_ranges) {
    const double n = k.count();
    if (!(n > 0.0)) continue;
    const double d = k.meanDistance(*radius_), reading = std::max(current.noise.stddev(d, current.bias), 1e-4);
    const double tape = current.bias.derivative(d) * k.tape_sigma_m;
    const double sigma = std::sqrt(reading * reading / n + tape * tape);
    ceres::LossFunction* loss = robust ? new ceres::HuberLoss(config_.huber_sigmas) : nullptr;
    problem.AddResidualBlock(knownRangeCost(config_.order, k, 1.0 / std::max(sigma, 1e-6)), loss, alpha_, radius_);
  }
}

/// Each stop tied to its commanded pose (seed 000 eq. 8; with the odometry scale, to the scaled
/// commanded path), or with the motion prior to the commanded step from the stop before (the
/// first stop's prior fixes the gauge).
void JointProblem::addPosePriors(ceres::Problem& problem) {
  const Pose2& c0 = obs_.commanded.front();
  for (std::size_t k = 0; k < poses_.size(); ++k) {
    const Pose2& c = obs_.commanded[k];
    const double yaw = poses_[k][2] + wrapAngle(c.yaw_rad - poses_[k][2]);  // unwrapped next to the estimate
    if (motion_ && k > 0) {
      const Pose2 step = stepBetween(obs_.commanded[k - 1], c);
      const double now = poses_[k][2] - poses_[k - 1][2];
      const double len = motionStepLength(obs_.commanded, k);
      problem.AddResidualBlock(
          new MotionPriorAnalyticCost(MotionPriorCost{
              step.x_m, step.y_m, now + wrapAngle(step.yaw_rad - now),
              1.0 / config_.motionStepSigma(len), 1.0 / config_.motionHeadingSigma(len)}),
          nullptr, poses_[k - 1], poses_[k], scale_);
      if (!fx_.odometry_scale) problem.SetParameterBlockConstant(scale_);
    } else if (fx_.odometry_scale) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ScaledPosePriorCost, 3, 3, 1>(new ScaledPosePriorCost{
                                   c.x_m, c.y_m, yaw, c0.x_m, c0.y_m, 1.0 / config_.sigma_s_m, 1.0 / config_.sigma_psi_rad}),
                               nullptr, poses_[k], scale_);
    } else {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PosePriorCost, 3, 3>(new PosePriorCost{
                                   c.x_m, c.y_m, yaw, 1.0 / config_.sigma_s_m, 1.0 / config_.sigma_psi_rad}),
                               nullptr, poses_[k]);
    }
    if (!fx_.estimate_heading && problem.HasParameterBlock(poses_[k]))
      problem.SetManifold(poses_[k], new ceres::SubsetManifold(3, {2}));
  }
  boundStepScale(problem);
}

/// Offsets: the first landmark is the reference (its offset is alpha_0's); others free when on.
/// The global terms that are off are held at zero.
void JointProblem::fixInactiveTerms(ceres::Problem& problem) {
  bool first = true;
  for (auto& [id, o] : offsets_) {
    if (!problem.HasParameterBlock(o)) continue;
    if (first || !fx_.landmark_offsets) problem.SetParameterBlockConstant(o);
    first = false;
  }
  std::vector<int> fixed;
  if (!fx_.drift) fixed.push_back(0);
  if (!fx_.angle_offset) fixed.push_back(1);
  if (!fx_.incidence_bias) fixed.push_back(2);
  if (fixed.size() == 3) problem.SetParameterBlockConstant(globals_);
  else if (!fixed.empty()) problem.SetManifold(globals_, new ceres::SubsetManifold(3, fixed));
}

/// Surveyed centres and measured poses are known, not estimated.
void JointProblem::fixKnownGeometry(ceres::Problem& problem) {
  for (const auto& [id, c] : config_.known_centres)
    if (auto it = centres_.find(id); it != centres_.end() && problem.HasParameterBlock(it->second))
      problem.SetParameterBlockConstant(it->second);
  for (const auto& [k, p] : config_.known_poses)
    if (k < poses_.size() && problem.HasParameterBlock(poses_[k])) problem.SetParameterBlockConstant(poses_[k]);
}

// ---------------------------------------------------------------------------------------------
// Solve loop

JointResult JointProblem::run() {
  selectReadings();
  if (readings_.size() < static_cast<std::size_t>(config_.order + 2) * 4) {
    out_.status.code = StatusCode::too_few_readings;
    out_.status.message = "too few landmark readings for the joint refinement (" + std::to_string(readings_.size()) + ")";
    return out_;
  }
  if (fx_.quantised) {
    std::vector<double> y;
    for (const auto& r : readings_) y.push_back(r.y_m);
    grid_ = detectReadingGrid(y);
  }
  previous_noise_size_ = noiseSize(out_.model.noise);
  weight_.assign(readings_.size(), 1.0);
  // Iteration 0 settles the geometry (poses, centres, radius) with the starting bias held;
  // later iterations free everything and re-estimate the noise law in between.
  for (int outer = config_.settle_geometry ? 0 : 1; outer <= config_.outer_iterations; ++outer) {
    if (!solve(outer)) return out_;
    if (outer > 0 && reestimateNoise(outer)) break;
  }
  out_.status.code = StatusCode::ok;
  reportEstimates();
  reportPriorLikelihood();
  reportEffects();
  reportLikelihood();
  reportBearingResiduals();
  if (config_.covariance) computeCovariance();
  return out_;
}

/// The standard deviation a reading is weighted and screened with: the noise law's, and on a
/// reading grid q the rounding's variance q^2 / 12 beside it (Sheppard's correction). Without it
/// the rounded model's unrounded scale (fitCellScale), 0.5 mm near the poles under a 20 mm grid,
/// made every rounding residual an outlier of the Huber loss and of the noise fits.
double JointProblem::workingSigma(std::size_t i, const RangeModel& m) const {
  const double s = sigmaOf(i, m);
  return std::max(grid_ > 0.0 ? std::sqrt(s * s + grid_ * grid_ / 12.0) : s, 1e-4);
}

/// One Ceres solve from the current estimate (outer 0: bias held). False when it failed.
bool JointProblem::solve(int outer) {
  out_.outer_iterations = outer;
  if (outer > 0 && config_.reselect && !config_.keep_all_beams) selectReadings();
  updateGeometry();
  sigma_.resize(readings_.size());
  RangeModel current = out_.model;
  current.bias.alpha = alphaVector();
  for (std::size_t i = 0; i < readings_.size(); ++i) sigma_[i] = workingSigma(i, current);
  if (outer > 0) updateResponsibilities(residualsNow(current.bias));  // E-step (weights 1 without mixed pixels)
  else weight_.assign(readings_.size(), 1.0);

  ceres::Problem::Options problem_options;
  ceres::Problem problem(problem_options);
  addResiduals(problem, true);
  if (!problem.HasParameterBlock(alpha_)) {
    out_.status.code = StatusCode::no_readings;
    out_.status.message = "no landmark reading left to fit";
    return false;
  }
  if (config_.estimate_radius) problem.SetParameterLowerBound(radius_, 0, 1e-3);
  if (outer == 0) problem.SetParameterBlockConstant(alpha_);

  ceres::Solver::Summary summary;
  ceres::Solve(solverOptions(motion_, config_.max_solver_iterations), &problem, &summary);
  out_.solver_iterations += static_cast<int>(summary.iterations.size());
  out_.converged = summary.termination_type == ceres::CONVERGENCE;
  if (!summary.IsSolutionUsable()) {
    out_.status.code = StatusCode::solver_failed;
    out_.status.message = "Ceres did not find a usable solution: " + summary.message;
    out_.converged = false;
    return false;
  }
  return true;
}

/// Re-estimates the noise law (and the mixed-pixel fraction, M-step) from the readings that are
/// not outliers. True when the law has settled.
bool JointProblem::reestimateNoise(int outer) {
  updateGeometry();
  BiasPolynomial f = out_.model.bias;
  f.alpha = alphaVector();
  const std::vector<double> res = residualsNow(f);
  if (fx_.mixed_pixels) reestimateMixedFraction(res);
  fitNoiseLaw(res, f);
  if (fx_.student_noise) fitStudent(res, f);
  if (grid_ > 0.0) fitCellScale(res);
  const double s_now = noiseSize(out_.model.noise);
  if (previous_noise_size_ > 0.0 && std::abs(s_now - previous_noise_size_) <= 1e-2 * previous_noise_size_) return true;
  previous_noise_size_ = s_now;
  if (outer == config_.outer_iterations) {
    out_.converged = false;
    out_.status.message = "noise model still changing after " + std::to_string(config_.outer_iterations) + " re-estimations";
  }
  return false;
}

void JointProblem::reestimateMixedFraction(const std::vector<double>& res) {
  updateResponsibilities(res);
  double sum = 0.0, n = 0.0;
  for (std::size_t i = 0; i < readings_.size(); ++i)
    if (readings_[i].edge) {
      sum += 1.0 - weight_[i];
      n += 1.0;
    }
  mixed_fraction_ = n > 0 ? std::clamp(sum / n, kMinMixedPixelFraction, 0.9) : 0.0;
}

/// The polynomial law by least squares on |residual|; the others as sigma_i = sigma_e h_i(kappa,
/// gamma): sigma_e profiled out, kappa and gamma by golden section.
void JointProblem::fitNoiseLaw(const std::vector<double>& res, const BiasPolynomial& f) {
  std::vector<std::size_t> in;  // readings used for the noise law
  for (std::size_t i = 0; i < readings_.size(); ++i)
    if (std::abs(res[i]) <= 4.0 * sigma_[i] && weight_[i] > 0.5) in.push_back(i);
  if (config_.noise == NoiseKind::polynomial) {
    std::vector<double> din, rin;
    for (std::size_t i : in) {
      din.push_back(geo_[i].d);
      rin.push_back(res[i]);
    }
    out_.model.noise.beta = fitNoisePolynomial(din, rin, config_.noise_order);
    return;
  }
  for (int pass = 0; pass < 2 && !config_.hold_noise_shape; ++pass) {
    if (fx_.noise_exponent) {
      out_.model.noise.exponent = goldenMax(
          [&](double k) {
            NoiseModel n = out_.model.noise;
            n.exponent = k;
            return profileNoise(n, gamma_, delta_, in, res, f, nullptr);
          },
          -1.0, 5.0);
    }
    if (fx_.incidence_noise)
      gamma_ = goldenMax([&](double g) { return profileNoise(out_.model.noise, g, delta_, in, res, f, nullptr); }, -1.0,
                         4.0);
    if (fx_.dark_noise && reference_intensity_ > 0.0)  // without intensities the factor is 1 whatever delta is
      delta_ = goldenMax([&](double x) { return profileNoise(out_.model.noise, gamma_, x, in, res, f, nullptr); }, -1.0,
                         3.0);
  }
  profileNoise(out_.model.noise, gamma_, delta_, in, res, f, &out_.model.noise.sigma_e);
}

/// Student-t noise: the scale sigma_e of the law's shape and nu, by EM on the readings within 30
/// sigma (beyond, the outlier floor's): t scale from the weighted squares, then nu by golden
/// section of the t log-likelihood (ECM), ten rounds.
void JointProblem::fitStudent(const std::vector<double>& res, const BiasPolynomial& f) {
  // A polynomial law is not a scale times a shape: there nu alone is fitted, its scale held.
  const bool scaled = config_.noise != NoiseKind::polynomial;
  std::vector<double> x;  // residual over the law's shape (polynomial law: over sigma)
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    if (!(std::abs(res[i]) <= 30.0 * sigma_[i])) continue;
    const double h = noiseShape(out_.model.noise, f, geo_[i].d, geo_[i].cos_inc, gamma_, readings_[i].darkness, delta_);
    x.push_back(res[i] / (scaled ? std::max(h, 1e-9) : sigma_[i]));
  }
  if (x.size() < 10) return;
  double nu = dof_ > 2.0 ? dof_ : 10.0;
  double t2 = out_.model.noise.sigma_e * out_.model.noise.sigma_e * (nu - 2.0) / nu;  // t scale squared
  for (int round = 0; round < 10; ++round) {
    double s = 0.0;
    for (double v : x) s += (nu + 1.0) / (nu + v * v / t2) * v * v;
    t2 = scaled ? std::max(s / static_cast<double>(x.size()), 1e-300) : (nu - 2.0) / nu;
    const double t = std::sqrt(t2);
    const double log_nu2 = goldenMax(
        [&](double l) {
          const double n = 2.0 + std::exp(l);
          double ll = 0.0;
          const double sd = scaled ? t * std::sqrt(n / (n - 2.0)) : 1.0;  // the t's standard deviation
          for (double v : x) ll += studentLogDensity(v, sd, n);
          return ll;
        },
        std::log(0.05), std::log(300.0));
    nu = 2.0 + std::exp(log_nu2);
  }
  dof_ = nu;
  if (scaled) out_.model.noise.sigma_e = std::sqrt(t2 * nu / (nu - 2.0));
}

/// Readings on a grid q (quantised): the noise law scaled by the factor c that maximises the
/// readings' cell probabilities (coreLogDensity with the grid; under Student-t noise the t's)
/// over the readings within 6 sigma that are not mixed pixels (30 under the t). The Gaussian fit's scale holds
/// the rounding's variance q^2/12 too; the cells carry it now.
void JointProblem::fitCellScale(const std::vector<double>& res) {
  // Under Student-t noise the weights are the t's, and its tails are fitted: within 30 sigma as fitStudent.
  const bool t = fx_.student_noise && dof_ > 2.0;
  std::vector<std::size_t> in;
  for (std::size_t i = 0; i < readings_.size(); ++i)
    if (std::abs(res[i]) <= (t ? 30.0 : 6.0) * sigma_[i] && (t || weight_[i] > 0.5)) in.push_back(i);
  if (in.size() < 10) return;
  RangeModel now = out_.model;
  now.bias.alpha = alphaVector();
  std::vector<double> s(in.size());
  for (std::size_t k = 0; k < in.size(); ++k) s[k] = std::max(sigmaOf(in[k], now), 1e-9);
  auto ll = [&](double log_c) {
    const double c = std::exp(log_c);
    double sum = 0.0;
    for (std::size_t k = 0; k < in.size(); ++k) {
      const double y = readings_[in[k]].y_m;
      sum += coreLogDensity(y, y - res[in[k]], c * s[k], fx_.student_noise ? dof_ : 0.0, grid_);
    }
    return sum;
  };
  const double c = std::exp(goldenMax(ll, std::log(1e-3), std::log(1.2)));
  if (config_.noise == NoiseKind::polynomial) {
    for (double& b : out_.model.noise.beta) b *= c;
  } else {
    out_.model.noise.sigma_e *= c;
  }
}

/// Profile log-likelihood (up to constants) of the law n with incidence exponent g over the
/// readings `in`; sigma_e (when asked) its maximising scale.
double JointProblem::profileNoise(NoiseModel n, double g, double delta, const std::vector<std::size_t>& in,
                                  const std::vector<double>& res, const BiasPolynomial& f, double* sigma_e) const {
  double s2 = 0.0, logh = 0.0;
  for (std::size_t i : in) {
    const double h = std::max(noiseShape(n, f, geo_[i].d, geo_[i].cos_inc, g, readings_[i].darkness, delta), 1e-9);
    s2 += res[i] * res[i] / (h * h);
    logh += std::log(h);
  }
  const double m = static_cast<double>(std::max<std::size_t>(in.size(), 1));
  s2 /= m;
  if (sigma_e) *sigma_e = std::sqrt(s2);
  return -0.5 * m * std::log(std::max(s2, 1e-300)) - logh;
}

// ---------------------------------------------------------------------------------------------
// Summary

/// Poses, centres, radius and bias into the result; landmark offsets are reported with mean
/// zero, their mean going into alpha_0.
void JointProblem::reportEstimates() {
  if (fx_.landmark_offsets && !offsets_.empty()) {
    double mean = 0.0;
    for (const auto& [id, o] : offsets_) mean += *o / static_cast<double>(offsets_.size());
    for (auto& [id, o] : offsets_) *o -= mean;
    alpha_[0] += mean;
  }
  out_.model.bias.alpha = alphaVector();
  out_.radius_m = *radius_;
  out_.poses.resize(poses_.size());
  double ps = 0.0, hs = 0.0;
  for (std::size_t k = 0; k < poses_.size(); ++k) {
    out_.poses[k] = Pose2{poses_[k][0], poses_[k][1], wrapAngle(poses_[k][2])};
    ps += std::pow(poses_[k][0] - obs_.commanded[k].x_m, 2) + std::pow(poses_[k][1] - obs_.commanded[k].y_m, 2);
    hs += std::pow(wrapAngle(poses_[k][2] - obs_.commanded[k].yaw_rad), 2);
  }
  out_.pose_scatter_m = std::sqrt(ps / (2.0 * static_cast<double>(poses_.size())));
  out_.heading_scatter_rad = std::sqrt(hs / static_cast<double>(poses_.size()));
  for (const auto& [id, c] : centres_) out_.centres[id] = Eigen::Vector2d(c[0], c[1]);
}

/// A fitted step scale stays within +-kMaxStepScale: odometry that misjudges its steps by half
/// is broken, not miscalibrated. Unbounded, an incidence bias hidden in a thin-pole drive drew
/// the scale to -0.99 (the path shrunk to a point, its misfit in the steps), which out-gained the
/// bias itself held out (docs/results/hidden-effects.md).
void JointProblem::boundStepScale(ceres::Problem& problem) const {
  if (!fx_.odometry_scale || !problem.HasParameterBlock(scale_) || problem.IsParameterBlockConstant(scale_)) return;
  problem.SetParameterLowerBound(scale_, 0, -kMaxStepScale);
  problem.SetParameterUpperBound(scale_, 0, kMaxStepScale);
}

/// NLL of the commanded positions (or steps, with the motion prior) given the refined poses.
/// With the motion prior the heading changes (and the first stop's heading) count too, as the
/// refinement weighs them (MotionPriorCost, PosePriorCost): a likelihood ratio of two drives'
/// fits then compares the objectives they minimised. Without it (stops) the headings' prior is
/// left out, as it has been since the stop-and-go diagnosis was calibrated on it.
void JointProblem::reportPriorLikelihood() {
  const Pose2& c0 = obs_.commanded.front();
  const double s = fx_.odometry_scale ? *scale_ : 0.0;
  auto add = [&](double ex, double ey, double sd) {
    out_.prior_neg_log_likelihood += 0.5 * (ex * ex + ey * ey) / (sd * sd) + kLog2Pi + 2.0 * std::log(sd);
  };
  auto addHeading = [&](double e, double sd) {
    out_.prior_neg_log_likelihood += 0.5 * e * e / (sd * sd) + 0.5 * kLog2Pi + std::log(sd);
  };
  for (std::size_t k = 0; k < poses_.size(); ++k) {
    if (motion_ && k > 0) {
      const Pose2 step = stepBetween(obs_.commanded[k - 1], obs_.commanded[k]);
      const Pose2 est = stepBetween(out_.poses[k - 1], out_.poses[k]);
      const double len = motionStepLength(obs_.commanded, k);
      add(est.x_m / (1.0 + s) - step.x_m, est.y_m / (1.0 + s) - step.y_m,  // where the noise is (MotionPriorCost)
          config_.motionStepSigma(len));
      addHeading(wrapAngle(out_.poses[k].yaw_rad - out_.poses[k - 1].yaw_rad - step.yaw_rad), config_.motionHeadingSigma(len));
      continue;
    }
    add(poses_[k][0] - (c0.x_m + (1.0 + s) * (obs_.commanded[k].x_m - c0.x_m)),
        poses_[k][1] - (c0.y_m + (1.0 + s) * (obs_.commanded[k].y_m - c0.y_m)), config_.sigma_s_m);
    if (motion_) addHeading(wrapAngle(out_.poses[k].yaw_rad - obs_.commanded[k].yaw_rad), config_.sigma_psi_rad);
  }
}

void JointProblem::reportEffects() {
  JointEffectEstimates& e = out_.effects;
  if (fx_.landmark_offsets)
    for (const auto& [id, o] : offsets_) e.landmark_offset_m[id] = *o;
  e.drift_m_per_scan = fx_.drift ? globals_[0] : 0.0;
  e.angle_offset_rad = fx_.angle_offset ? globals_[1] : 0.0;
  e.incidence_bias_m = fx_.incidence_bias ? globals_[2] : 0.0;
  e.incidence_noise_exponent = gamma_;
  e.noise_exponent = out_.model.noise.kind == NoiseKind::power ? out_.model.noise.exponent
                     : out_.model.noise.kind == NoiseKind::constant ? 0.0
                                                                     : 2.0;
  e.mixed_pixel_fraction = fx_.mixed_pixels ? mixed_fraction_ : 0.0;
  e.odometry_scale = fx_.odometry_scale ? *scale_ : 0.0;
  e.student_dof = fx_.student_noise ? dof_ : 0.0;
  e.range_grid_m = grid_;
  e.dark_noise_exponent = delta_;
  e.dark_reference_intensity = reference_intensity_;
  e.heading_rms_rad = out_.heading_scatter_rad;
  out_.effect_parameters = (fx_.landmark_offsets ? static_cast<int>(offsets_.size()) - 1 : 0) + (fx_.drift ? 1 : 0) +
                           (fx_.angle_offset ? 1 : 0) + (fx_.incidence_bias ? 1 : 0) + (fx_.incidence_noise ? 1 : 0) +
                           (fx_.noise_exponent ? 1 : 0) + (fx_.mixed_pixels ? 1 : 0) + (fx_.odometry_scale ? 1 : 0) +
                           (fx_.student_noise ? 1 : 0) + (fx_.quantised ? 1 : 0) + (fx_.dark_noise ? 1 : 0) +
                           (fx_.estimate_heading ? static_cast<int>(poses_.size()) : 0);
}

/// Likelihood at the solution (all readings, with the mixed-pixel and outlier terms) and the
/// information criteria.
void JointProblem::reportLikelihood() {
  updateGeometry();
  const JointEffectEstimates& e = out_.effects;
  out_.neg_log_likelihood = 0.0;
  out_.outliers = 0;
  out_.residual_rms_m = 0.0;
  std::vector<double> d(readings_.size());
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    d[i] = geo_[i].d;
    const double s = std::max(sigmaOf(i, out_.model), 1e-6);
    const double mean = meanOf(i, out_.model.bias);
    const double r = (readings_[i].y_m - mean) / s;
    out_.neg_log_likelihood -= readingLogLikelihood(readings_[i].y_m, mean, s,
                                                    readings_[i].edge ? e.mixed_pixel_fraction : 0.0,
                                                    config_.outlier_floor, out_.window_min_m, window_max_, e.student_dof,
                                                    e.range_grid_m);
    out_.residual_rms_m += r * r * s * s;
    if (std::abs(r) > config_.huber_sigmas * 2.0) ++out_.outliers;
  }
  out_.residual_rms_m = std::sqrt(out_.residual_rms_m / static_cast<double>(readings_.size()));
  out_.readings = readings_.size();
  out_.distances_m = d;
  out_.readings_m.reserve(readings_.size());
  for (const auto& r : readings_) out_.readings_m.push_back(r.y_m);
  const int heading_params = fx_.estimate_heading ? static_cast<int>(poses_.size()) : 0;
  const double k = static_cast<double>(config_.order + 1) +
                   (config_.noise == NoiseKind::polynomial ? config_.noise_order + 1.0 : 1.0) +
                   (config_.estimate_radius ? 1.0 : 0.0) + static_cast<double>(out_.effect_parameters - heading_params);
  out_.aic = 2.0 * k + 2.0 * out_.neg_log_likelihood;
  out_.bic = k * std::log(static_cast<double>(readings_.size())) + 2.0 * out_.neg_log_likelihood;
}

/// Centre-bearing residuals: detected centre bearing against the refined geometry.
void JointProblem::reportBearingResiduals() {
  double bs = 0.0;
  std::size_t bn = 0;
  for (const auto& s : obs_.sightings) {
    auto it = out_.centres.find(s.landmark);
    if (it == out_.centres.end() || s.stop >= out_.poses.size()) continue;
    const Pose2& p = out_.poses[s.stop];
    const double predicted =
        std::atan2(it->second.y() - p.y_m, it->second.x() - p.x_m) - p.yaw_rad - out_.effects.angle_offset_rad;
    bs += std::pow(wrapAngle(s.bearing_rad - predicted), 2);
    ++bn;
  }
  out_.sigma_theta_rad = bn ? std::sqrt(bs / static_cast<double>(bn)) : 0.0;
}

/// Covariance of alpha, the radius and the centres with the final weights; the pose priors fix
/// the gauge.
void JointProblem::computeCovariance() {
  for (std::size_t i = 0; i < readings_.size(); ++i) sigma_[i] = workingSigma(i, out_.model);
  ceres::Problem problem;
  addResiduals(problem, false);
  ceres::Covariance::Options copt;
  // A dense SVD of the whole Jacobian (rank-revealing: a pseudo-inverse where the data leave a
  // direction free) costs readings x parameters memory: over 20 GB for a 4791-pose CARMEN log.
  // Beyond a few hundred poses the sparse QR computes the same blocks (the pose priors make the
  // Jacobian full rank) in memory that grows with the poses.
  if (problem.NumParameters() <= config_.dense_covariance_max_parameters) {
    copt.algorithm_type = ceres::DENSE_SVD;
    copt.null_space_rank = -1;
  } else {
    copt.algorithm_type = ceres::SPARSE_QR;
  }
  auto cov = std::make_unique<ceres::Covariance>(copt);
  std::vector<std::pair<const double*, const double*>> blocks = {{alpha_, alpha_}};
  const bool radius_free = config_.estimate_radius && problem.HasParameterBlock(radius_);
  if (radius_free) {
    blocks.emplace_back(alpha_, radius_);
    blocks.emplace_back(radius_, radius_);
  }
  for (auto& [id, c] : centres_)
    if (problem.HasParameterBlock(c)) blocks.emplace_back(c, c);
  const bool has_alpha = problem.HasParameterBlock(alpha_);
  bool computed = has_alpha && cov->Compute(blocks, &problem);
  if (!computed && has_alpha && copt.algorithm_type == ceres::SPARSE_QR) {
    // The sparse QR needs full rank; a landmark whose few beams leave its centre free along a
    // direction (seen once, edge-on: Freiburg 079) makes it fail where the dense SVD would take
    // a pseudo-inverse. Tie every centre to its estimate with 100 m standard deviation: that
    // removes the null space and changes the determined blocks by about (sigma/100 m)^2.
    for (auto& [id, c] : centres_)
      if (problem.HasParameterBlock(c))
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<WeakPointPriorCost, 2, 2>(
                                     new WeakPointPriorCost{c[0], c[1], kWeakCentrePriorSigmaM}),
                                 nullptr, c);
    cov = std::make_unique<ceres::Covariance>(copt);
    computed = cov->Compute(blocks, &problem);
  }
  if (!computed) return;
  const int n = config_.order + 1;
  out_.alpha_covariance.resize(n, n);
  cov->GetCovarianceBlock(alpha_, alpha_, out_.alpha_covariance.data());
  if (radius_free) {
    out_.alpha_radius_covariance.resize(n);
    cov->GetCovarianceBlock(alpha_, radius_, out_.alpha_radius_covariance.data());
    cov->GetCovarianceBlock(radius_, radius_, &out_.radius_variance);
  }
  for (auto& [id, c] : centres_) {
    if (!problem.HasParameterBlock(c)) continue;
    Eigen::Matrix2d m;
    cov->GetCovarianceBlock(c, c, m.data());
    out_.centre_covariance[id] = m;
  }
}

}  // namespace lidarcal::calibration::joint
