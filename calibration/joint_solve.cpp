// SPDX-License-Identifier: BSD-3-Clause
// The solve loop of the joint refinement: Ceres solves from the current estimate, each followed
// by the noise law (and the mixed-pixel fraction, a Student t's weights, a grid's cell scale)
// re-estimated from the residuals until it settles.
#include "calibration/joint_problem.hpp"

#include <algorithm>
#include <cmath>

#include "calibration/range_model_fit.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration::joint {
namespace {

/// Size of a noise law, to tell when its re-estimation has settled.
double noiseSize(const NoiseModel& n) {
  if (n.kind == NoiseKind::polynomial)
    return n.beta.empty() ? 0.0 : std::abs(n.beta.front()) + std::abs(n.beta.back());
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

}  // namespace

JointResult JointProblem::run() {
  selectReadings();
  if (readings_.size() < static_cast<std::size_t>(config_.order + 2) * 4) {
    out_.status.code = StatusCode::too_few_readings;
    out_.status.message = "too few landmark readings for the joint refinement (" +
                          std::to_string(readings_.size()) + ")";
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
  // E-step (weights 1 without mixed pixels)
  if (outer > 0)
    updateResponsibilities(residualsNow(current.bias));
  else
    weight_.assign(readings_.size(), 1.0);

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
  if (previous_noise_size_ > 0.0 &&
      std::abs(s_now - previous_noise_size_) <= 1e-2 * previous_noise_size_)
    return true;
  previous_noise_size_ = s_now;
  if (outer == config_.outer_iterations) {
    out_.converged = false;
    out_.status.message = "noise model still changing after " +
                          std::to_string(config_.outer_iterations) + " re-estimations";
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
      gamma_ = goldenMax(
          [&](double g) { return profileNoise(out_.model.noise, g, delta_, in, res, f, nullptr); },
          -1.0, 4.0);
    // without intensities the factor is 1 whatever delta is
    if (fx_.dark_noise && reference_intensity_ > 0.0)
      delta_ = goldenMax(
          [&](double x) { return profileNoise(out_.model.noise, gamma_, x, in, res, f, nullptr); },
          -1.0, 3.0);
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
    const double h = noiseShape(
        out_.model.noise, f, {geo_[i].d, geo_[i].cos_inc, gamma_, readings_[i].darkness, delta_});
    x.push_back(res[i] / (scaled ? std::max(h, 1e-9) : sigma_[i]));
  }
  if (x.size() < 10) return;
  double nu = dof_ > 2.0 ? dof_ : 10.0;
  // t scale squared
  double t2 = out_.model.noise.sigma_e * out_.model.noise.sigma_e * (nu - 2.0) / nu;
  for (int round = 0; round < 10; ++round) {
    double s = 0.0;
    for (double v : x) s += (nu + 1.0) / (nu + v * v / t2) * v * v;
    t2 = scaled ? std::max(s / static_cast<double>(x.size()), 1e-300) : (nu - 2.0) / nu;
    const double t = std::sqrt(t2);
    const double log_nu2 = goldenMax(
        [&](double l) {
          const double n = 2.0 + std::exp(l);
          double ll = 0.0;
          // the t's standard deviation
          const double sd = scaled ? t * std::sqrt(n / (n - 2.0)) : 1.0;
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
/// over the readings within 6 sigma that are not mixed pixels (30 under the t). The Gaussian fit's
/// scale holds the rounding's variance q^2/12 too; the cells carry it now.
void JointProblem::fitCellScale(const std::vector<double>& res) {
  // Under Student-t noise the weights are the t's, and its tails are fitted: within 30 sigma as
  // fitStudent.
  const bool t = fx_.student_noise && dof_ > 2.0;
  std::vector<std::size_t> in;
  for (std::size_t i = 0; i < readings_.size(); ++i)
    if (std::abs(res[i]) <= (t ? 30.0 : 6.0) * sigma_[i] && (t || weight_[i] > 0.5))
      in.push_back(i);
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
double JointProblem::profileNoise(NoiseModel n, double g, double delta,
                                  const std::vector<std::size_t>& in,
                                  const std::vector<double>& res, const BiasPolynomial& f,
                                  double* sigma_e) const {
  double s2 = 0.0, logh = 0.0;
  for (std::size_t i : in) {
    const double h = std::max(
        noiseShape(n, f, {geo_[i].d, geo_[i].cos_inc, g, readings_[i].darkness, delta}), 1e-9);
    s2 += res[i] * res[i] / (h * h);
    logh += std::log(h);
  }
  const double m = static_cast<double>(std::max<std::size_t>(in.size(), 1));
  s2 /= m;
  if (sigma_e) *sigma_e = std::sqrt(s2);
  return -0.5 * m * std::log(std::max(s2, 1e-300)) - logh;
}
}  // namespace lidarcal::calibration::joint
