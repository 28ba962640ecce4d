// Model criticism (diagnosis/): the statistics against closed forms, the simulator's
// effects against their definitions, the joint refinement's effect terms recover known values,
// and diagnose names an effect hidden in simulated data (which one and its size drawn from a
// case seed the assertion does not look at).
//
// Hidden-effect cases per effect: LIDARCAL_DIAGNOSE_CASES (default 10 for the clean data and
// angle_offset, at least 9 named; 5 for the other effects, at least 4 named), case seeds from
// LIDARCAL_DIAGNOSE_FIRST (default 21: disjoint from the seeds 1-20 the method was developed on),
// LIDARCAL_DIAGNOSE_REPLICAS bootstrap replicas (default 5); with 20 cases and 19 replicas
// (ctest -L long, configured with -DLIDARCAL_LONG_TESTS=ON) at least 19 named.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <random>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "diagnosis/sequence.hpp"
#include "diagnosis/static_scene.hpp"
#include "diagnosis/stats.hpp"
#include "diagnosis/tails.hpp"
#include "calibration/joint_refinement.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "common/rng.hpp"
#include "io/scene_io.hpp"
#include "simulation/simulator.hpp"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

/// Hidden-effect cases of `effect` (LIDARCAL_DIAGNOSE_CASES for every effect). By default 10 for
/// the clean data and angle_offset, the two whose fresh rate is below 20 of 20
/// (docs/results/hidden-effects.md), and 5 for the others: a case costs about 4 s of CPU (candidate
/// fits and cross-validation, not the replicas), and 10 for every effect would make the default
/// suite about 60 % longer, against a budget of 30 %. A deliberate bug that breaks an effect's
/// likelihood ratio or its sign fails its check in every case, so 5 cases catch it as surely as 10.
int casesPerEffect(const std::string& effect) {
  const char* env = std::getenv("LIDARCAL_DIAGNOSE_CASES");
  if (env && *env) return std::max(1, std::atoi(env));
  return effect == "none" || effect == "angle_offset" ? 10 : 5;
}

/// Bootstrap replicas of the hidden-effect runs (LIDARCAL_DIAGNOSE_REPLICAS). The default run
/// takes the fewest the method allows (5) to keep the suite's time; the long run and
/// docs/results/hidden-effects.md take the command's default (19).
int replicasPerCase() {
  const char* env = std::getenv("LIDARCAL_DIAGNOSE_REPLICAS");
  return env && *env ? std::max(5, std::atoi(env)) : 5;
}

/// A stream tag from a case's name (FNV-1a: the same on every platform).
std::uint64_t nameTag(const std::string& name) {
  std::uint64_t h = 14695981039346656037ULL;
  for (unsigned char ch : name) h = (h ^ ch) * 1099511628211ULL;
  return h;
}

/// Seeds for the hidden effects, drawn from a seed the tests do not read (data generated with seeds
/// the tests do not choose), one stream per `tag`, disjoint in practice from the development seeds
/// (all below 1000).
std::vector<std::uint64_t> unreadSeeds(std::uint64_t tag, int n) {
  auto rng = makeRng(20261125, tag);
  std::uniform_int_distribution<std::uint64_t> seed_of(1000, 1000000);
  std::vector<std::uint64_t> out(static_cast<std::size_t>(n));
  for (auto& s : out) s = seed_of(rng);
  return out;
}

/// Case seeds of the hidden-effect runs of `effect`: n consecutive from LIDARCAL_DIAGNOSE_FIRST
/// when it is set (the long run and docs/results/hidden-effects.md: 21-40), else drawn by
/// unreadSeeds.
std::vector<std::uint64_t> caseSeeds(const std::string& effect, int n) {
  const char* env = std::getenv("LIDARCAL_DIAGNOSE_FIRST");
  if (env && *env) {
    std::vector<std::uint64_t> out;
    for (int k = 0; k < n; ++k) out.push_back(static_cast<std::uint64_t>(std::max(1, std::atoi(env)) + k));
    return out;
  }
  return unreadSeeds(nameTag(effect), n);
}

// ---------------------------------------------------------------------------------------------
// Statistics.

TEST(DiagnoseStats, HolmMatchesTheStepDownByHand) {
  // Sorted p: 0.01 (x4 = 0.04), 0.02 (x3 = 0.06), 0.03 (x2 = 0.06), 0.5 (x1 = 0.5).
  const auto adj = holmAdjust({0.03, 0.5, 0.01, 0.02});
  EXPECT_NEAR(adj[2], 0.04, 1e-12);
  EXPECT_NEAR(adj[3], 0.06, 1e-12);
  EXPECT_NEAR(adj[0], 0.06, 1e-12);  // monotone: max(0.06, 0.06)
  EXPECT_NEAR(adj[1], 0.5, 1e-12);
  const auto with_nan = holmAdjust({0.01, std::nan(""), 0.04});
  EXPECT_NEAR(with_nan[0], 0.02, 1e-12);
  EXPECT_TRUE(std::isnan(with_nan[1]));
  EXPECT_NEAR(with_nan[2], 0.04, 1e-12);
}

TEST(DiagnoseStats, LikelihoodRatioAndCombinedPValues) {
  // Chi-square with one degree of freedom: the tabulated 5 % and 1 % points.
  EXPECT_NEAR(likelihoodRatioPValue(3.841459, 1), 0.05, 1e-6);
  EXPECT_NEAR(likelihoodRatioPValue(6.634897, 1), 0.01, 1e-6);
  EXPECT_EQ(likelihoodRatioPValue(-0.5, 1), 1.0);
  EXPECT_TRUE(std::isnan(likelihoodRatioPValue(10.0, 3)));  // one parameter only
  // On the bound of its range the null is half 0, half chi-square: its 5 % and 1 % points are
  // chi-square's 10 % and 2 % points.
  EXPECT_NEAR(boundedLikelihoodRatioPValue(2.705543), 0.05, 1e-6);
  EXPECT_NEAR(boundedLikelihoodRatioPValue(5.411894), 0.01, 1e-6);
  EXPECT_EQ(boundedLikelihoodRatioPValue(0.0), 1.0);
  // Bonferroni over the tests that apply.
  EXPECT_NEAR(combinedPValue(0.2, 0.01, 0.003), 0.009, 1e-15);
  EXPECT_NEAR(combinedPValue(0.2, 0.01, std::nan("")), 0.02, 1e-15);
  EXPECT_NEAR(combinedPValue(0.9, 0.8, 0.7), 1.0, 1e-15);
  EXPECT_TRUE(std::isnan(combinedPValue(std::nan(""), std::nan(""), std::nan(""))));
}

TEST(DiagnoseStats, BlockTridiagonalInverseAndLogDetMatchTheDenseOnes) {
  // A chain of 9 poses: random information per pose (readings) plus random couplings between
  // neighbours (odometry steps), assembled as J^T J so that the matrix is positive definite.
  auto rng = makeRng(11, 3);
  std::normal_distribution<double> n01(0.0, 1.0);
  const int n = 9;
  std::vector<Eigen::Matrix3d> diag(n, Eigen::Matrix3d::Zero()), upper(n, Eigen::Matrix3d::Zero());
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  auto random3 = [&] {
    Eigen::Matrix3d m;
    for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = n01(rng);
    return m;
  };
  for (int k = 0; k < n; ++k) {
    const Eigen::Matrix3d j = random3();
    const Eigen::Matrix3d info = j.transpose() * j * (k % 3 == 1 ? 1e-3 : 1.0);  // some poses nearly unseen
    diag[k] += info;
    dense.block<3, 3>(3 * k, 3 * k) += info;
  }
  for (int k = 0; k + 1 < n; ++k) {
    const Eigen::Matrix3d ja = random3(), jb = random3();
    diag[k] += ja.transpose() * ja;
    diag[k + 1] += jb.transpose() * jb;
    upper[k] += ja.transpose() * jb;
    dense.block<3, 3>(3 * k, 3 * k) += ja.transpose() * ja;
    dense.block<3, 3>(3 * k + 3, 3 * k + 3) += jb.transpose() * jb;
    dense.block<3, 3>(3 * k, 3 * k + 3) += ja.transpose() * jb;
    dense.block<3, 3>(3 * k + 3, 3 * k) += jb.transpose() * ja;
  }
  const Eigen::MatrixXd inverse = dense.inverse();
  std::vector<Eigen::Matrix3d> off;
  const auto blocks = diagnosis::blockTridiagonalInverseDiagonal(diag, upper, &off);
  ASSERT_EQ(blocks.size(), static_cast<std::size_t>(n));
  ASSERT_EQ(off.size(), static_cast<std::size_t>(n - 1));
  for (int k = 0; k < n; ++k) {
    const Eigen::Matrix3d want = inverse.block<3, 3>(3 * k, 3 * k);
    EXPECT_LT((blocks[k] - want).norm(), 1e-8 * want.norm()) << "block " << k;
    if (k + 1 == n) continue;
    const Eigen::Matrix3d want_off = inverse.block<3, 3>(3 * k, 3 * k + 3);
    EXPECT_LT((off[k] - want_off).norm(), 1e-8 * want.norm()) << "block " << k << ", " << k + 1;
  }
  EXPECT_TRUE(diagnosis::blockTridiagonalInverseDiagonal({}, {}).empty());
  EXPECT_THROW(diagnosis::blockTridiagonalInverseDiagonal(diag, {}), std::invalid_argument);
  // Its log-determinant (the restricted likelihood's term for the poses) from the same pass.
  const double log_det = std::log(dense.determinant());
  EXPECT_NEAR(diagnosis::blockTridiagonalLogDet(diag, upper), log_det, 1e-9 * std::abs(log_det));
  std::vector<Eigen::Matrix3d> indefinite = diag;
  indefinite[2] = -indefinite[2];
  EXPECT_TRUE(std::isnan(diagnosis::blockTridiagonalLogDet(indefinite, upper)));
}

TEST(DiagnoseStats, LeaveOneOutLogDensityMatchesTheRefitWithoutTheBlock) {
  // A linear Gaussian model in 6 parameters (two poses), observed in blocks of 3 rows with unit
  // noise: the formula from the fit on every block against the predictive density of the block
  // under the fit without it.
  auto rng = makeRng(17, 4);
  std::normal_distribution<double> n01(0.0, 1.0);
  const int blocks = 5;
  std::vector<Eigen::Matrix<double, 3, 6>> j(blocks);
  std::vector<Eigen::Vector3d> y(blocks);
  for (int b = 0; b < blocks; ++b) {
    for (int i = 0; i < 18; ++i) j[b](i / 6, i % 6) = n01(rng) * (b == 0 ? 0.2 : 1.0);  // block 0: little leverage
    for (int i = 0; i < 3; ++i) y[b](i) = n01(rng) * 2.0;  // residuals of any size
  }
  auto fit = [&](int without, Eigen::Matrix<double, 6, 1>& theta, Eigen::Matrix<double, 6, 6>& cov) {
    Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    for (int b = 0; b < blocks; ++b)
      if (b != without) {
        h += j[b].transpose() * j[b];
        g += j[b].transpose() * y[b];
      }
    cov = h.inverse();
    theta = cov * g;
  };
  Eigen::Matrix<double, 6, 1> theta;
  Eigen::Matrix<double, 6, 6> cov;
  fit(-1, theta, cov);
  for (int k = 0; k < blocks; ++k) {
    Eigen::Matrix<double, 6, 1> theta_k;
    Eigen::Matrix<double, 6, 6> cov_k;
    fit(k, theta_k, cov_k);
    const Eigen::Vector3d e = y[k] - j[k] * theta_k;
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() + j[k] * cov_k * j[k].transpose();
    const double want = -0.5 * e.dot(p.inverse() * e) - 0.5 * std::log(p.determinant()) - 1.5 * std::log(2.0 * std::acos(-1.0));
    const Eigen::Vector3d r = y[k] - j[k] * theta;
    const double got = diagnosis::leaveOneOutLogDensity(r, j[k] * cov * j[k].transpose());
    EXPECT_NEAR(got, want, 1e-9 * std::max(1.0, std::abs(want))) << "block " << k;
  }
  // A block that alone determines a direction of the parameters: S has an eigenvalue 1.
  EXPECT_TRUE(std::isnan(diagnosis::leaveOneOutLogDensity(Eigen::Vector3d(1.0, 0.0, 0.0), Eigen::Matrix3d::Identity())));
}

namespace {
/// poleDistanceMoments(1.2, perp, v, r, extra) against the sampled moments of
/// along - q - extra r cos(phi) over the draws whose beam hits the pole (q = sqrt(r^2 - perp^2),
/// cos(phi) = q / r clamped as the model clamps it), for miss distances far inside the tangent,
/// near it, at it and past it (the fit's miss distance outside the pole while the reading came from it).
void expectPoleMomentsMatchSamples(double r, double extra) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (const double perp : {0.0, 0.015, 0.024, 0.0275, 0.029, -0.031}) {
    for (const double sp : {0.0005, 0.002, 0.006}) {
      Eigen::Matrix2d v;
      v << 4e-6, 0.6 * 2e-3 * sp, 0.6 * 2e-3 * sp, sp * sp;
      const Eigen::Matrix2d l = v.llt().matrixL();
      double n = 0.0, m = 0.0, m2 = 0.0;
      for (int k = 0; k < 400000; ++k) {
        const Eigen::Vector2d x = Eigen::Vector2d(1.2, perp) + l * Eigen::Vector2d(n01(rng), n01(rng));
        if (std::abs(x(1)) >= r) continue;
        const double q = std::sqrt(r * r - x(1) * x(1));
        const double d = x(0) - q - extra * r * std::max(q / r, 0.05);
        n += 1.0;
        m += d;
        m2 += d * d;
      }
      if (n < 2000.0) continue;  // too few hits to check against
      m /= n;
      const double var = m2 / n - m * m;
      const auto got = diagnosis::poleDistanceMoments(1.2, perp, v, r, extra);
      const double se_mean = std::sqrt(var / n);
      EXPECT_NEAR(got.mean, m, 5.0 * se_mean + 2e-5) << "perp " << perp << " sd " << sp << " extra " << extra;
      EXPECT_NEAR(got.var, var, 0.05 * var) << "perp " << perp << " sd " << sp << " extra " << extra;
    }
  }
}
}  // namespace

TEST(DiagnoseStats, PoleDistanceMomentsMatchSampledHits) {
  // The distance along a beam to a pole of radius 2.75 cm when the ray's closest approach and
  // miss distance are uncertain (correlated normals).
  constexpr double r = 0.0275;
  expectPoleMomentsMatchSamples(r, 0.0);
  // No spread at all: the ray's own distance (its closest approach when it misses).
  EXPECT_DOUBLE_EQ(diagnosis::poleDistanceMoments(1.0, 0.03, Eigen::Matrix2d::Zero(), r).mean, 1.0);
  EXPECT_DOUBLE_EQ(diagnosis::poleDistanceMoments(1.0, 0.0, Eigen::Matrix2d::Zero(), r).mean, 1.0 - r);
}

TEST(DiagnoseStats, PoleReadingMomentsWithAnIncidenceBiasMatchSampledHits) {
  // A reading with an incidence bias b moves with the miss distance as along - (1 + b / r) q:
  // b 3.3 cm on r 2.75 cm, and a small b; the sampled moments the test computes itself.
  constexpr double r = 0.0275;
  expectPoleMomentsMatchSamples(r, 0.033 / r);
  expectPoleMomentsMatchSamples(r, 0.004 / r);
  // The extra root's variance: far inside the tangent, to first order (1 + c)^2 times the distance's.
  Eigen::Matrix2d v;
  v << 0.0, 0.0, 0.0, 1e-8;
  const double plain = diagnosis::poleDistanceMoments(1.0, 0.01, v, r).var;
  EXPECT_NEAR(diagnosis::poleDistanceMoments(1.0, 0.01, v, r, 1.2).var, 2.2 * 2.2 * plain, 1e-6 * plain);
  // With no spread: the root and its extra share at the given miss distance.
  const double q = std::sqrt(r * r - 0.01 * 0.01);
  EXPECT_NEAR(diagnosis::poleDistanceMoments(1.0, 0.01, Eigen::Matrix2d::Zero(), r, 1.2).mean, 1.0 - q - 1.2 * q, 1e-12);
}

TEST(DiagnoseStats, KolmogorovSmirnovDistance) {
  EXPECT_DOUBLE_EQ(ksDistance({1, 2, 3}, {1, 2, 3}), 0.0);
  EXPECT_DOUBLE_EQ(ksDistance({1, 2, 3}, {4, 5, 6}), 1.0);
  EXPECT_NEAR(ksDistance({1, 2, 3, 4}, {3, 4, 5, 6}), 0.5, 1e-12);
}

TEST(DiagnoseStats, ReplicaPValueIsCalibratedForNormalStatistics) {
  // Over many draws of (statistic, 19 replicas) from one normal law, p < 0.05 about 5 % of the time.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(3.0, 2.0);
  int below = 0;
  constexpr int kTrials = 4000;
  for (int t = 0; t < kTrials; ++t) {
    std::vector<double> r(19);
    for (double& v : r) v = n(rng);
    below += replicaPValue(n(rng), r, true) < 0.05;
  }
  EXPECT_NEAR(static_cast<double>(below) / kTrials, 0.05, 0.012);
  double es = 0.0;
  EXPECT_LT(replicaPValue(100.0, {0, 1, -1, 0.5, -0.5}, false, &es), 1e-4);
  EXPECT_GT(es, 50.0);
  EXPECT_GT(replicaPValue(-100.0, {0, 1, -1, 0.5, -0.5}, false), 0.99);  // one-sided: below is fine
}

TEST(DiagnoseStats, GridResultantTellsQuantisedReadings) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(1.0, 3.0);
  std::vector<double> cont, grid;
  for (int i = 0; i < 5000; ++i) {
    cont.push_back(u(rng));
    grid.push_back(quantise(cont.back(), 1e-3));
  }
  EXPECT_GT(gridResultant(grid, 1e-3), 0.999);
  EXPECT_LT(gridResultant(cont, 1e-3), 0.05);
  EXPECT_LT(gridResultant(grid, 2e-3), 0.05);  // a coarser grid than the readings' (half on it, half between)
}

TEST(DiagnoseStats, HeldOutPValue) {
  EXPECT_DOUBLE_EQ(heldoutPValue(-0.1, 0.01), 1.0);
  EXPECT_NEAR(heldoutPValue(0.02, 0.01), 0.5 * std::erfc(2.0 / std::sqrt(2.0)), 1e-12);
  EXPECT_TRUE(std::isnan(heldoutPValue(0.02, 0.0)));
}

TEST(DiagnoseStats, CauseNamingRules) {
  auto cand = [](Effect e, double p, double gain, double se, int k, bool id = true) {
    CandidateResult c;
    c.effect = e;
    c.p_value = p;
    c.heldout_gain_nats_per_point = gain;
    c.heldout_gain_se = se;
    c.parameters = k;
    c.identifiable = id;
    return c;
  };
  const Effect a = Effect::incidence_noise, b = Effect::incidence_bias, c = Effect::range_drift, d = Effect::mixed_pixels;
  const Effect per_stop = Effect::heading_error, common = Effect::angle_offset;
  std::string why;
  std::vector<CandidateResult> none = {cand(a, 0.2, 0.001, 0.001, 1), cand(b, 0.5, -0.01, 0.001, 1)};
  EXPECT_EQ(nameCause(none, 0.01, why), cause::kNone);
  // Largest significant gain wins.
  std::vector<CandidateResult> two = {cand(a, 1e-9, 0.01, 0.001, 1), cand(b, 1e-12, 0.05, 0.001, 1)};
  EXPECT_EQ(nameCause(two, 0.01, why), toString(b));
  // A simpler effect nested in the top one, within two standard errors, is preferred (parsimony);
  // one that is not nested is not.
  std::vector<CandidateResult> nested = {cand(per_stop, 1e-12, 0.0105, 0.001, 10), cand(common, 1e-12, 0.0100, 0.001, 1)};
  EXPECT_EQ(nameCause(nested, 0.01, why, {{common, per_stop}}), toString(common));
  EXPECT_EQ(nameCause(nested, 0.01, why), toString(per_stop));
  // A significant effect that cannot be estimated apart from the baseline.
  std::vector<CandidateResult> confounded = {cand(a, 1e-12, 0.05, 0.001, 1, false), cand(b, 1e-9, 0.01, 0.001, 1)};
  EXPECT_EQ(nameCause(confounded, 0.01, why), cause::kNotIdentifiable);
  // Two effects that explain the data alike and are declared indistinguishable.
  std::vector<CandidateResult> twins = {cand(a, 1e-12, 0.0500, 0.002, 1), cand(b, 1e-12, 0.0495, 0.002, 1)};
  EXPECT_EQ(nameCause(twins, 0.01, why, {}, {{a, b}}), cause::kNotIdentifiable);
  // Holm: p = 0.004 is not significant among four candidates at alpha 0.01.
  std::vector<CandidateResult> holm = {cand(a, 0.004, 0.01, 0.001, 1), cand(b, 0.9, 0, 1, 1), cand(c, 0.9, 0, 1, 1),
                                       cand(d, 0.9, 0, 1, 1)};
  EXPECT_EQ(nameCause(holm, 0.01, why), cause::kNone);
}

// ---------------------------------------------------------------------------------------------
// The simulator's effects against their definitions.

TEST(SimulatorEffects, EffectReadingMatchesTheDefinitionAtEveryIncidence) {
  // y = f(d) + b (1 - cos phi) + offset + c t + sigma(d) (1 / cos phi)^gamma e is linear in e:
  // the reading at e = 0 is the mean and y(e = 1) - y(e = 0) the standard deviation, exactly.
  // Several incidences, so that no single one can hide a wrong form (at cos phi = 0.5,
  // 1 - cos phi equals cos phi and 1 / cos phi - 1 equals 1).
  RangeModel m;
  m.bias.alpha = {0.05, 0.9, 0.05};
  m.noise.kind = NoiseKind::squared;
  m.noise.sigma_e = 0.002;
  std::mt19937_64 unused(1);
  const double d = 2.5;
  for (double b : {0.03, -0.02}) {
    for (double gamma : {1.0, 1.5}) {
      RangeEffects fx;
      fx.incidence_noise_exponent = gamma;
      fx.incidence_bias_m = b;
      fx.range_drift_m_per_scan = 1e-4;
      for (double cos_inc : {1.0, 0.95, 0.8, 0.5, 0.3, 0.1}) {
        SCOPED_TRACE(testing::Message() << "b " << b << ", gamma " << gamma << ", cos phi " << cos_inc);
        const double mean = m.bias(d) + b * (1.0 - cos_inc) + 0.01 + 1e-4 * 100;
        const double y0 = simulation::effectReading(m, fx, d, {cos_inc, 0.01, 100}, 0.0, unused);
        const double y1 = simulation::effectReading(m, fx, d, {cos_inc, 0.01, 100}, 1.0, unused);
        EXPECT_NEAR(y0, mean, 1e-12);
        EXPECT_NEAR(y1 - y0, m.noise.stddev(d, m.bias) * std::pow(1.0 / cos_inc, gamma), 1e-12);
      }
      // Grazing beams are treated as at cos phi = 0.05 (87 degrees).
      EXPECT_NEAR(simulation::effectReading(m, fx, d, {0.01, 0.0, 0}, 0.0, unused), m.bias(d) + b * 0.95, 1e-12);
    }
  }
  // The bias grows away from normal incidence (b > 0: longer readings at grazing incidence).
  RangeEffects fx;
  fx.incidence_bias_m = 0.03;
  EXPECT_GT(simulation::effectReading(m, fx, d, {0.2, 0.0, 0}, 0.0, unused),
            simulation::effectReading(m, fx, d, {0.9, 0.0, 0}, 0.0, unused));
  // The drift is zero at its reference scan and grows by c per scan from there (one convention
  // for the simulator and the fits: c (t - t_ref)).
  RangeEffects drift;
  drift.range_drift_m_per_scan = 2e-4;
  drift.range_drift_reference_scan = 40.0;
  EXPECT_NEAR(simulation::effectReading(m, drift, d, {1.0, 0.0, 40}, 0.0, unused), m.bias(d), 1e-12);
  EXPECT_NEAR(simulation::effectReading(m, drift, d, {1.0, 0.0, 50}, 0.0, unused), m.bias(d) + 2e-4 * 10, 1e-12);
  EXPECT_NEAR(simulation::effectReading(m, drift, d, {1.0, 0.0, 0}, 0.0, unused), m.bias(d) - 2e-4 * 40, 1e-12);
  // Every effect off: exactly rangeReading().
  EXPECT_DOUBLE_EQ(simulation::effectReading(m, RangeEffects{}, d, {0.3, 0.0, 7}, 0.7, unused),
                   simulation::rangeReading(m, d, 0.7));
}

TEST(SimulatorEffects, StudentNoiseKeepsTheVarianceAndQuantisationTheGrid) {
  RangeModel m;
  m.noise.kind = NoiseKind::constant;
  m.noise.sigma_e = 0.01;
  RangeEffects fx;
  fx.noise_student_dof = 4.0;
  fx.range_resolution_m = 0.001;
  std::mt19937_64 rng(9), fxrng(10);
  std::normal_distribution<double> n(0.0, 1.0);
  constexpr int kN = 40000;
  double s2 = 0.0, s4 = 0.0;
  for (int i = 0; i < kN; ++i) {
    const double y = simulation::effectReading(m, fx, 2.0, {}, n(rng), fxrng);
    EXPECT_NEAR(y / 0.001, std::round(y / 0.001), 1e-6);
    s2 += (y - 2.0) * (y - 2.0) / kN;
    s4 += std::pow(y - 2.0, 4) / kN;
  }
  EXPECT_NEAR(s2 / (0.01 * 0.01), 1.0, 0.1);           // unit-variance t (quantisation adds 1/12 mm^2)
  EXPECT_GT(s4 / (s2 * s2), 4.0);                       // heavier tails than a normal (kurtosis 3)
}

TEST(SimulatorEffects, MixedPixelsOnlyAtTheEdgesAndAtTheRequestedRate) {
  auto c = test::paperFieldLandmarkLevel();
  c.effects.mixed_pixel_fraction = 0.3;
  c.model.noise.sigma_e = 0.0;  // noise-free: a mixed reading is the only way to be off
  const auto s = simulation::simulateLandmarkLevel(c, 4);
  double edges = 0, mixed_edges = 0, inner_off = 0;
  for (std::size_t i = 0; i < s.obs.sightings.size(); ++i) {
    const auto& b = s.obs.sightings[i].beams;
    for (std::size_t j = 0; j < b.size(); ++j) {
      const bool off = std::abs(b[j].range_m - c.model.bias(s.true_range_m[i][j])) > 1e-9;
      if (j == 0 || j + 1 == b.size()) {
        edges += 1;
        mixed_edges += off;
      } else {
        inner_off += off;
      }
    }
  }
  EXPECT_EQ(inner_off, 0);
  EXPECT_NEAR(mixed_edges / edges, 0.3, 0.05);  // nearly every edge beam has a wall behind it here
}

TEST(SimulatorEffects, SceneKeysRoundTripAndStayAbsentWhenOff) {
  const auto file = std::filesystem::temp_directory_path() / ("lidarcal-effects-" + std::to_string(::getpid()) + ".json");
  {
    std::ofstream out(file);
    out << R"({"sensor": {"range_min_m": 0.1, "range_max_m": 8,
                          "effects": {"incidence_noise_exponent": 1.5, "incidence_bias_m": 0.02,
                                      "range_drift_m_per_scan": 0.0001, "mixed_pixel_fraction": 0.05,
                                      "noise_student_dof": 4, "range_resolution_m": 0.001}},
               "path": {"step_error_fraction": 0.03},
               "landmarks": [{"x_m": 1, "y_m": 2, "radius_m": 0.1, "range_offset_m": 0.02}],
               "walls": [{"x0_m": 0, "y0_m": 5, "x1_m": 3, "y1_m": 5, "range_offset_m": -0.01}]})";
  }
  const Scene s = io::readScene(file);
  std::filesystem::remove(file);
  EXPECT_EQ(s.sensor.effects.incidence_noise_exponent, 1.5);
  EXPECT_EQ(s.sensor.effects.incidence_bias_m, 0.02);
  EXPECT_EQ(s.sensor.effects.range_drift_m_per_scan, 0.0001);
  EXPECT_EQ(s.sensor.effects.mixed_pixel_fraction, 0.05);
  EXPECT_EQ(s.sensor.effects.noise_student_dof, 4.0);
  EXPECT_EQ(s.sensor.effects.range_resolution_m, 0.001);
  EXPECT_EQ(s.path.step_error_fraction, 0.03);
  EXPECT_EQ(s.landmarks[0].range_offset_m, 0.02);
  EXPECT_EQ(s.walls[0].range_offset_m, -0.01);
  const auto j = io::sceneToJson(s);
  EXPECT_EQ(j["sensor"]["effects"]["noise_student_dof"], 4.0);
  EXPECT_EQ(j["walls"][0]["range_offset_m"], -0.01);
  Scene off = s;
  off.sensor.effects = RangeEffects{};
  off.path.step_error_fraction = 0.0;
  off.landmarks[0].range_offset_m = 0.0;
  const auto k = io::sceneToJson(off);
  EXPECT_FALSE(k["sensor"].contains("effects"));
  EXPECT_FALSE(k["path"].contains("step_error_fraction"));
  EXPECT_FALSE(k["landmarks"][0].contains("range_offset_m"));
}

TEST(SimulatorEffects, StepErrorScalesTheTruePath) {
  Scene s;
  s.path.stops = 5;
  s.path.step_m = 0.4;
  s.path.step_error_fraction = 0.05;
  const auto stops = simulation::planStops(s, 1);
  for (std::size_t k = 0; k < stops.size(); ++k) EXPECT_NEAR(stops[k].actual.x_m, 0.42 * static_cast<double>(k), 1e-12);
}

// ---------------------------------------------------------------------------------------------
// The joint refinement's effect terms recover known values.

struct Recovery {
  const char* name;
  void (*hide)(simulation::LandmarkLevelConfig&);
  void (*enable)(JointEffects&);
  double (*estimate)(const JointResult&);
  double truth;
  double tolerance;
};

class JointEffectRecovery : public ::testing::TestWithParam<Recovery> {};

TEST_P(JointEffectRecovery, RecoversTheTermFromTheCommandedPoses) {
  const Recovery& r = GetParam();
  auto c = test::paperFieldLandmarkLevel();
  r.hide(c);
  const auto s = simulation::simulateLandmarkLevel(c, 11);
  JointConfig jc;
  jc.keep_all_beams = true;
  jc.reselect = false;
  jc.covariance = false;
  jc.estimate_radius = false;
  jc.effects.estimate_heading = false;
  r.enable(jc.effects);
  JointInit init;
  for (const auto& st : s.stops) init.poses.push_back(st.commanded);
  for (std::size_t l = 0; l < c.landmarks.size(); ++l)
    init.centres[static_cast<int>(l) + 1] = Eigen::Vector2d(c.landmarks[l].x_m, c.landmarks[l].y_m);
  init.radius_m = 0.12;
  init.model = c.model;
  init.model.noise.kind = NoiseKind::squared;
  init.model.noise.sigma_e = 0.0019176;
  const JointResult f = refineJoint(s.obs, init, jc);
  ASSERT_TRUE(f.ok()) << f.status.name() << ": " << f.status.message;
  EXPECT_NEAR(r.estimate(f), r.truth, r.tolerance) << r.name;
  // Signed terms: the fitted sign is the hidden one (the tolerance is below the size, so the
  // check above implies it; stated on its own for the message).
  EXPECT_EQ(std::signbit(r.estimate(f)), std::signbit(r.truth)) << r.name << ": fitted " << r.estimate(f);
}

INSTANTIATE_TEST_SUITE_P(
    EachTerm, JointEffectRecovery,
    ::testing::Values(
        Recovery{"drift", [](auto& c) { c.effects.range_drift_m_per_scan = 3e-4; }, [](auto& e) { e.drift = true; },
                 [](const JointResult& f) { return f.effects.drift_m_per_scan; }, 3e-4, 3e-5},
        Recovery{"angle", [](auto& c) { c.mount_yaw_rad = deg2rad(2.0); }, [](auto& e) { e.angle_offset = true; },
                 [](const JointResult& f) { return rad2deg(f.effects.angle_offset_rad); }, 2.0, 0.3},
        Recovery{"incidence_bias", [](auto& c) { c.effects.incidence_bias_m = 0.03; }, [](auto& e) { e.incidence_bias = true; },
                 [](const JointResult& f) { return f.effects.incidence_bias_m; }, 0.03, 0.005},
        // Every signed term also with the other sign.
        Recovery{"drift_negative", [](auto& c) { c.effects.range_drift_m_per_scan = -3e-4; }, [](auto& e) { e.drift = true; },
                 [](const JointResult& f) { return f.effects.drift_m_per_scan; }, -3e-4, 3e-5},
        Recovery{"angle_negative", [](auto& c) { c.mount_yaw_rad = deg2rad(-2.0); }, [](auto& e) { e.angle_offset = true; },
                 [](const JointResult& f) { return rad2deg(f.effects.angle_offset_rad); }, -2.0, 0.3},
        Recovery{"incidence_bias_negative", [](auto& c) { c.effects.incidence_bias_m = -0.03; },
                 [](auto& e) { e.incidence_bias = true; }, [](const JointResult& f) { return f.effects.incidence_bias_m; }, -0.03,
                 0.005},
        Recovery{"landmark_offset_negative", [](auto& c) { c.landmarks[2].range_offset_m = -0.04; },
                 [](auto& e) { e.landmark_offsets = true; },
                 [](const JointResult& f) { return f.effects.landmark_offset_m.at(3) - f.effects.landmark_offset_m.at(1); }, -0.04,
                 0.005},
        Recovery{"landmark_offset", [](auto& c) { c.landmarks[2].range_offset_m = 0.04; },
                 [](auto& e) { e.landmark_offsets = true; },
                 [](const JointResult& f) { return f.effects.landmark_offset_m.at(3) - f.effects.landmark_offset_m.at(1); }, 0.04,
                 0.005},
        // The true steps 4 % longer (shorter) than commanded; the radius is given, so the scale
        // is separable from the bias.
        Recovery{"odometry_scale", [](auto& c) { c.path.step_error_fraction = 0.04; }, [](auto& e) { e.odometry_scale = true; },
                 [](const JointResult& f) { return f.effects.odometry_scale; }, 0.04, 0.01},
        Recovery{"odometry_scale_negative", [](auto& c) { c.path.step_error_fraction = -0.04; },
                 [](auto& e) { e.odometry_scale = true; }, [](const JointResult& f) { return f.effects.odometry_scale; }, -0.04,
                 0.01},
        Recovery{"incidence_noise", [](auto& c) { c.effects.incidence_noise_exponent = 1.0; },
                 [](auto& e) { e.incidence_noise = true; },
                 [](const JointResult& f) { return f.effects.incidence_noise_exponent; }, 1.0, 0.2},
        Recovery{"noise_exponent",
                 [](auto& c) {
                   c.model.noise.kind = NoiseKind::power;
                   c.model.noise.exponent = 1.0;
                   c.model.noise.sigma_e = 0.006;
                 },
                 [](auto& e) { e.noise_exponent = true; }, [](const JointResult& f) { return f.effects.noise_exponent; }, 1.0, 0.2},
        Recovery{"mixed_pixels", [](auto& c) { c.effects.mixed_pixel_fraction = 0.2; }, [](auto& e) { e.mixed_pixels = true; },
                 [](const JointResult& f) { return f.effects.mixed_pixel_fraction; }, 0.2, 0.06},
        // Student-t noise of 4 degrees of freedom (same variance): about 5,000 readings hold nu
        // to a few tenths.
        Recovery{"student_noise", [](auto& c) { c.effects.noise_student_dof = 4.0; }, [](auto& e) { e.student_noise = true; },
                 [](const JointResult& f) { return f.effects.student_dof; }, 4.0, 1.2},
        // Readings rounded to 1 cm: the grid is found, and the noise scale fitted on the cells is
        // the unrounded noise's (a Gaussian fit's holds the rounding's q^2 / 12 as well, more than
        // the noise itself near the poles); -1 when the grid is not the hidden one.
        Recovery{"quantised", [](auto& c) { c.effects.range_resolution_m = 0.01; }, [](auto& e) { e.quantised = true; },
                 [](const JointResult& f) { return f.effects.range_grid_m == 0.01 ? f.model.noise.sigma_e / 0.0019176 : -1.0; },
                 1.0, 0.1},
        // Poles of intensity 20, 40, 80, 160 and 320, noise growing as (I_ref / I)^0.75: a
        // black pole reads 2.8 times as noisy as a mid-grey one.
        Recovery{"dark", [](auto& c) {
                   for (std::size_t l = 0; l < c.landmarks.size(); ++l) c.landmarks[l].intensity = 20.0 * std::pow(2.0, l);
                   c.effects.dark_noise_exponent = 0.75;
                   c.effects.dark_reference_intensity = 80.0;
                 },
                 [](auto& e) { e.dark_noise = true; }, [](const JointResult& f) { return f.effects.dark_noise_exponent; },
                 0.75, 0.1}),
    [](const auto& p) { return std::string(p.param.name); });

// ---------------------------------------------------------------------------------------------
// Hidden effects in sequences.

class HiddenEffect : public ::testing::TestWithParam<const char*> {};

/// Hidden case h simulated and diagnosed with diagnose seed `seed` and `replicas` bootstrap
/// replicas; one replica for the extended simulation, whose closeness these tests do not look at.
DiagnosisResult diagnoseCase(const test::HiddenEffectCase& h, std::uint64_t seed, int replicas) {
  const auto s = simulation::simulateLandmarkLevel(h.config, h.seed);
  DiagnoseConfig dc;
  dc.seed = seed;
  dc.replicas = replicas;
  dc.closeness_replicas = 1;
  return diagnoseSequence(s.obs, dc);
}

/// The candidate row of effect `e` in `r` (nullptr when `e` was not a candidate).
const CandidateResult* candidateFor(const DiagnosisResult& r, Effect e) {
  const auto c = std::find_if(r.candidates.begin(), r.candidates.end(), [e](const CandidateResult& x) { return x.effect == e; });
  return c == r.candidates.end() ? nullptr : &*c;
}

/// The hidden size of a signed effect (0: not signed) and the key of its estimate.
std::pair<double, const char*> signedTruth(const std::string& e, const test::HiddenEffectCase& h) {
  if (e == "incidence_bias") return {h.config.effects.incidence_bias_m, "incidence_bias_m"};
  if (e == "range_drift") return {h.config.effects.range_drift_m_per_scan, "range_drift_m_per_scan"};
  if (e == "angle_offset") return {h.config.mount_yaw_rad, "angle_offset_deg"};
  return {0.0, ""};
}

TEST_P(HiddenEffect, DiagnoseNamesItAndItsSignAndItsLikelihoodRatio) {
  // Case seeds drawn from a seed the test does not read (caseSeeds), away from the seeds 1-40
  // the method was developed and measured on.
  const std::string e = GetParam();
  const int n = casesPerEffect(e);
  int named = 0, signs = 0, signed_cases = 0, lr_significant = 0, lr_cases = 0;
  std::string misses;
  for (const std::uint64_t k : caseSeeds(e, n)) {
    SCOPED_TRACE(k);
    const auto h = test::hiddenEffectCase(e, k);
    const auto r = diagnoseCase(h, k, replicasPerCase());
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    if (r.primary_cause == e) ++named;
    else misses += " case " + std::to_string(k) + " (" + h.size + "): " + r.primary_cause + ";";
    const std::optional<Effect> hidden = parseEffect(e);
    const CandidateResult* c = hidden ? candidateFor(r, *hidden) : nullptr;
    if (!c) continue;  // none
    // One-parameter effects: the likelihood ratio of the nested fits (extended against the
    // seeds' model) on all the data finds the hidden effect.
    if (std::isfinite(c->p_likelihood_ratio)) {
      ++lr_cases;
      lr_significant += c->p_likelihood_ratio < 0.01;
    }
    // Signed effects: the fitted sign is the hidden one.
    const auto [truth, key] = signedTruth(e, h);
    if (truth != 0.0) {
      ++signed_cases;
      ASSERT_TRUE(c->estimates.count(key)) << key;
      signs += std::signbit(c->estimates.at(key)) == std::signbit(truth);
    }
  }
  // Binomial allowance: at least n - 1 of n. A method that is right with probability 0.99 per
  // case fails 9 of 10 with probability 0.4 % (4 of 5: 0.1 %), one right with 0.95 with 8.6 %
  // (2.3 %); the long run (20 cases, ctest -L long) asks 19 of 20. Fewer than 5 cases: all.
  auto required = [](int cases) { return cases >= 20 ? (19 * cases + 19) / 20 : cases >= 5 ? cases - 1 : cases; };
  EXPECT_GE(named, required(n)) << e << ": named in " << named << " of " << n << ";" << misses;
  EXPECT_GE(lr_significant, required(lr_cases)) << e << ": likelihood ratio p < 0.01 in " << lr_significant << " of " << lr_cases;
  EXPECT_GE(signs, required(signed_cases)) << e << ": fitted sign right in " << signs << " of " << signed_cases;
}

INSTANTIATE_TEST_SUITE_P(Sequence, HiddenEffect,
                         ::testing::Values("none", "incidence_noise", "incidence_bias", "landmark_bias", "heading_error",
                                           "range_drift", "mixed_pixels", "angle_offset", "range_noise_law", "heavy_tails",
                                           "quantisation", "dark_surface"),
                         [](const auto& p) { return std::string(p.param); });

/// Effects in readings rounded to whole millimetres, as every real sensor reports them. The
/// squared law's noise is 0.5 mm at 0.5 m, so the rounding is real and its model gains held out
/// (+0.01 nats per reading): a hidden effect is named when it holds beside the rounding
/// (SequenceDiagnosis::nameBeside), clean data are `none` or `quantisation`, never a physical
/// effect. Three cases per effect whose seeds come from a seed this test does not read, 5
/// bootstrap replicas each.
class OnAMillimetreGrid : public ::testing::TestWithParam<const char*> {};

TEST_P(OnAMillimetreGrid, TheEffectIsNamedBesideTheRounding) {
  const std::string e = GetParam();
  int named = 0;
  std::string misses;
  for (const std::uint64_t k : unreadSeeds(nameTag(e + " on a 1 mm grid"), 3)) {
    SCOPED_TRACE(k);
    auto h = test::hiddenEffectCase(e, k);
    h.config.effects.range_resolution_m = 0.001;
    const auto r = diagnoseCase(h, k, 5);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    const bool right = e == "none" ? r.primary_cause == "none" || r.primary_cause == "quantisation" : r.primary_cause == e;
    named += right;
    if (!right) misses += " case " + std::to_string(k) + " (" + h.size + "): " + r.primary_cause + " [" + r.decision + "];";
    // The grid is found whatever is named.
    const CandidateResult* q = candidateFor(r, Effect::quantisation);
    ASSERT_NE(q, nullptr);
    ASSERT_TRUE(q->applicable) << q->note;
    EXPECT_EQ(q->estimates.at("grid_m"), 0.001);
  }
  // At least 2 of 3: a method right with probability 0.95 per case fails that with 0.7 %
  // (an angle offset alone is named in 19 of 20, the clean data `none` in 19 of 20 off a grid).
  EXPECT_GE(named, 2) << e << ":" << misses;
}

INSTANTIATE_TEST_SUITE_P(Sequence, OnAMillimetreGrid, ::testing::Values("none", "angle_offset", "incidence_noise", "landmark_bias"),
                         [](const auto& p) { return std::string(p.param); });

/// Effects where the poles return intensities of 15 to 250 (black to white) and the noise does
/// not depend on them: the dark-surface candidate is fitted (applicable) and must not take the
/// place of the hidden effect, nor be named in clean data. Three cases per effect whose seeds
/// come from a seed this test does not read, 5 bootstrap replicas each.
class WithIntensities : public ::testing::TestWithParam<const char*> {};

TEST_P(WithIntensities, TheDarkSurfaceModelTakesNoOtherEffectsPlace) {
  const std::string e = GetParam();
  int named = 0;
  std::string misses;
  for (const std::uint64_t k : unreadSeeds(nameTag(e + " with intensities"), 3)) {
    SCOPED_TRACE(k);
    auto h = test::hiddenEffectCase(e, k);
    test::giveIntensities(h.config, k);
    const auto r = diagnoseCase(h, k, 5);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    named += r.primary_cause == e;
    if (r.primary_cause != e) misses += " case " + std::to_string(k) + " (" + h.size + "): " + r.primary_cause + " [" + r.decision + "];";
    const CandidateResult* d = candidateFor(r, Effect::dark_surface);
    ASSERT_NE(d, nullptr);
    ASSERT_TRUE(d->applicable) << d->note;
    EXPECT_FALSE(d->significant) << "dark_surface significant with noise independent of intensity: " << r.decision;
  }
  EXPECT_GE(named, 2) << e << ":" << misses;
}

INSTANTIATE_TEST_SUITE_P(Sequence, WithIntensities, ::testing::Values("none", "incidence_noise", "landmark_bias"),
                         [](const auto& p) { return std::string(p.param); });

TEST(DiagnoseSequence, WithoutIntensitiesTheDarkSurfaceModelIsNotApplicable) {
  // The paper field as the seeds simulate it: no intensity recorded. The candidate is listed, not
  // fitted, and says what to record.
  const auto h = test::hiddenEffectCase("none", 5);
  const auto r = diagnoseCase(h, 5, 5);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  const CandidateResult* d = candidateFor(r, Effect::dark_surface);
  ASSERT_NE(d, nullptr);
  EXPECT_FALSE(d->applicable);
  EXPECT_NE(d->note.find("intensit"), std::string::npos) << d->note;
  EXPECT_FALSE(d->significant);
}

TEST(DiagnoseSequence, AnAngleOffsetUnderHeavyTailsIsNamedByItsLikelihoodRatioBesideTheT) {
  // A lidar yawed 2-3 degrees in Student-t noise of 3 degrees of freedom: the t comes first, and
  // the offset's evidence is in sample (its held-out gain beside the t is about 2 standard errors),
  // so it is named by the likelihood ratio of the two t fits (SequenceDiagnosis:: nameBeside; named
  // in 18 of 20 fresh cases, docs/results/hidden-effects.md). Three cases whose seeds come from a
  // seed this test does not read, at least 2 named.
  int named = 0;
  std::string misses;
  for (const std::uint64_t k : unreadSeeds(nameTag("angle offset under tails"), 3)) {
    SCOPED_TRACE(k);
    auto h = test::hiddenEffectCase("angle_offset", k);
    h.config.effects.noise_student_dof = 3.0;
    const auto r = diagnoseCase(h, k, 5);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    named += r.primary_cause == "angle_offset";
    if (r.primary_cause != "angle_offset") misses += " case " + std::to_string(k) + ": " + r.primary_cause + " [" + r.decision + "];";
    const CandidateResult* a = candidateFor(r, Effect::angle_offset);
    ASSERT_NE(a, nullptr);
    if (r.primary_cause == "angle_offset" && a->estimates.count("heldout_gain_beside_tails")) {
      EXPECT_TRUE(a->estimates.count("p_likelihood_ratio_beside_tails")) << r.decision;
    }
  }
  EXPECT_GE(named, 2) << misses;
}

TEST(DiagnoseSequence, APhysicalEffectUnderHeavyTailsIsNamedAndTheTailsStayBesideIt) {
  // Per-pole range offsets (RMS 2-2.5 cm) in Student-t noise of 3 degrees of freedom: the named
  // cause must be physical. Either the offsets gain most, or the t comes first and the offsets hold
  // beside it (refitted with the t, held out: SequenceDiagnosis::refineCause; in 3 of 5 development
  // cases). Three cases whose seeds come from a seed this test does not read.
  int beside = 0;
  for (const std::uint64_t k : unreadSeeds(nameTag("offsets under tails"), 3)) {
    SCOPED_TRACE(k);
    auto h = test::hiddenEffectCase("landmark_bias", k);
    h.config.effects.noise_student_dof = 3.0;
    const auto r = diagnoseCase(h, k, 5);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    EXPECT_EQ(r.primary_cause, "landmark_bias") << r.decision;
    for (const auto& c : r.candidates) {
      if (c.effect == Effect::heavy_tails) {
        EXPECT_TRUE(c.significant);
        EXPECT_LT(c.estimates.at("student_dof"), 6.0);
      }
      // Checked beside the t: the gain over the t alone is reported with its standard error.
      if (c.effect == Effect::landmark_bias && c.estimates.count("heldout_gain_beside_tails")) {
        ++beside;
        EXPECT_GT(c.estimates.at("heldout_gain_beside_tails"), 3.0 * c.estimates.at("heldout_gain_beside_tails_se"));
      }
    }
    std::printf("case %llu: %s (%s)\n", static_cast<unsigned long long>(k), r.primary_cause.c_str(), r.decision.c_str());
  }
  std::printf("checked beside the tails in %d of 3\n", beside);
}

TEST(DiagnoseSequence, ResultCarriesEveryCandidateAndTheExtendedModel) {
  const auto h = test::hiddenEffectCase("landmark_bias", 3);
  const auto s = simulation::simulateLandmarkLevel(h.config, h.seed);
  DiagnoseConfig dc;
  const auto r = diagnoseSequence(s.obs, dc, &s.true_range_m);
  ASSERT_STREQ(r.status.name(), "ok");
  EXPECT_EQ(r.mode, DiagnoseMode::sequence);
  std::vector<std::string> names;
  for (const auto& c : r.candidates) names.push_back(toString(c.effect));
  for (const char* e : {"incidence_noise", "incidence_bias", "landmark_bias", "heading_error", "range_drift", "mixed_pixels",
                        "angle_offset", "range_noise_law", "heavy_tails"})
    EXPECT_NE(std::find(names.begin(), names.end(), e), names.end()) << e;
  ASSERT_EQ(r.primary_cause, "landmark_bias");
  // The offsets are recovered (relative to their mean, as simulated): the estimates explain most
  // of the pattern. Part of a landmark's offset moves its centre along the lines of sight, so
  // single offsets are not exact; their error stays well below the pattern's own size.
  double mean = 0.0;
  for (const auto& l : h.config.landmarks) mean += l.range_offset_m / 5.0;
  double ss_true = 0.0, ss_err = 0.0;
  for (int id = 1; id <= 5; ++id) {
    const double truth = h.config.landmarks[static_cast<std::size_t>(id - 1)].range_offset_m - mean;
    const double est = r.extended_parameters.at("landmark_offset_m[" + std::to_string(id) + "]");
    ss_true += truth * truth;
    ss_err += (est - truth) * (est - truth);
  }
  EXPECT_LT(std::sqrt(ss_err), 0.35 * std::sqrt(ss_true)) << "error " << std::sqrt(ss_err / 5) << " m RMS";
  EXPECT_TRUE(r.scene_keys.count("landmarks[0].range_offset_m (id 1)"));
  // The extended simulation is closer to the data, and calibrating with the offsets is better.
  EXPECT_LT(r.closeness_extended.variance_ratio_median_abs_log, r.closeness_baseline.variance_ratio_median_abs_log);
  EXPECT_GT(r.calibration_mse_ratio_extended, r.calibration_mse_ratio_baseline);
}

TEST(DiagnoseSequence, ADriftsSceneKeysGiveItsReferenceScanBesideTheFittedOffset) {
  // The joint refinement's drift is zero at the mean scan; the scene keys that simulate the named
  // drift carry that reference scan, with the fitted alpha_0 unshifted.
  const auto h = test::hiddenEffectCase("range_drift", 21);
  const auto s = simulation::simulateLandmarkLevel(h.config, h.seed);
  DiagnoseConfig dc;
  dc.replicas = 5;
  dc.closeness_replicas = 1;
  const auto r = diagnoseSequence(s.obs, dc);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  ASSERT_EQ(r.primary_cause, toString(Effect::range_drift)) << r.decision;
  ASSERT_TRUE(r.scene_keys.count("sensor.effects.range_drift_reference_scan"));
  double last = 0.0;
  for (const auto& sg : s.obs.sightings) last = std::max(last, static_cast<double>(sg.scan));
  const double t_ref = r.scene_keys.at("sensor.effects.range_drift_reference_scan");
  EXPECT_GT(t_ref, 0.25 * last);
  EXPECT_LT(t_ref, 0.75 * last);
  ASSERT_FALSE(r.extended_bias_alpha.empty());
  EXPECT_EQ(r.scene_keys.at("sensor.bias_alpha[0]"), r.extended_bias_alpha[0]);
  EXPECT_EQ(r.scene_keys.at("sensor.effects.range_drift_m_per_scan"), r.extended_parameters.at("range_drift_m_per_scan"));
}

TEST(DiagnoseSequence, AStepLengthErrorIsNotIdentifiableWithoutTheRadius) {
  auto h = test::hiddenEffectCase("odometry_scale", 2);
  h.config.publish_radius = false;
  const auto s = simulation::simulateLandmarkLevel(h.config, h.seed);
  DiagnoseConfig dc;
  dc.candidates = {Effect::odometry_scale, Effect::range_drift};
  const auto r = diagnoseSequence(s.obs, dc);
  ASSERT_STREQ(r.status.name(), "ok");
  ASSERT_EQ(r.candidates.size(), 2u);
  // The world's scale and the radius are free together: the bias polynomial absorbs the step error.
  EXPECT_FALSE(r.candidates[0].identifiable) << "se " << r.candidates[0].standard_error;
  EXPECT_FALSE(r.candidates[0].note.empty());
  EXPECT_TRUE(r.candidates[1].identifiable);
  EXPECT_NE(r.primary_cause, "odometry_scale");
}

TEST(DiagnoseSequence, NoLandmarkGivesAStatus) {
  LandmarkObservations obs;
  obs.commanded = {Pose2{}, Pose2{0.3, 0, 0}, Pose2{0.6, 0, 0}};
  const auto r = diagnoseSequence(obs, DiagnoseConfig{});
  EXPECT_STRNE(r.status.name(), "ok");
  EXPECT_FALSE(r.status.message.empty());
}

// ---------------------------------------------------------------------------------------------
// Static recordings: a simulated room seen from one pose.

using test::staticRoom;
NoiseModel squared(double sigma_e) { return test::squaredNoise(sigma_e); }

TEST(DiagnoseStatic, CleanRoomHasNoCauseAndFindsItsWalls) {
  DiagnoseConfig dc;
  dc.replicas = 9;
  std::vector<WallLine> walls;
  const auto r = diagnoseStatic(staticRoom({}, squared(0.0015), 3), dc, &walls);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  EXPECT_EQ(r.mode, DiagnoseMode::static_scene);
  EXPECT_EQ(r.primary_cause, cause::kNone) << r.decision;
  EXPECT_GE(walls.size(), 4u);
  EXPECT_NEAR(r.baseline_extra.at("alpha0_m"), 0.01, 4.0 * r.baseline_extra.at("alpha0_se_m") + 0.002);
  EXPECT_NEAR(r.baseline.noise.sigma_e, 0.0015, 0.0002);
  for (const auto& c : r.candidates) {
    if (c.effect == Effect::heading_error || c.effect == Effect::angle_offset) {
      EXPECT_FALSE(c.applicable);
    }
  }
}

class StaticHiddenEffect : public ::testing::TestWithParam<test::StaticCase> {};

TEST_P(StaticHiddenEffect, DiagnoseNamesWhatTheTruthAllows) {
  const test::StaticCase& c = GetParam();
  DiagnoseConfig dc;
  dc.replicas = 9;
  dc.static_range_offset_m = c.known_offset_m;
  // One room whose seed comes from a seed this test does not read (the rates over seeds:
  // docs/results/static-diagnosis.md).
  const std::uint64_t seed = unreadSeeds(nameTag(c.name), 1).front();
  dc.seed = seed;
  const auto r = diagnoseStatic(staticRoom(c, seed), dc);
  SCOPED_TRACE(seed);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  if (!c.also.empty()) {
    EXPECT_TRUE(c.allows(r.primary_cause)) << r.primary_cause << ": " << r.decision;
  } else {
    EXPECT_EQ(r.primary_cause, c.effect) << r.decision;
  }
  for (const auto& k : r.candidates) {
    if (k.effect == Effect::heading_error || k.effect == Effect::angle_offset || k.effect == Effect::odometry_scale) {
      EXPECT_FALSE(k.applicable) << toString(k.effect);  // one pose: no stops, no headings
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Room, StaticHiddenEffect, ::testing::ValuesIn(test::staticCases()),
                         [](const auto& p) { return std::string(p.param.name); });

TEST(DiagnoseStatic, ATurningSensorIsDiagnosedInWindowsAndItsEdgesNamed) {
  // The sensor turns in place by 0.05 degree per scan (3 degrees over the recording); its readings
  // follow the seeds' model exactly. The diagnosis sees the motion (windows of 8 scans, each with a
  // time trend per beam), and what the motion does to the data: a beam that sweeps across the
  // pillar's or the box's edge within a window reads now the near, now the far surface, which is
  // what the mixed-pixel candidate describes. No range effect of the sensor may be named.
  const StaticScans s = staticRoom({}, squared(0.0015), 5, 64, 0.0, deg2rad(0.05));
  DiagnoseConfig dc;
  dc.replicas = 5;
  const auto r = diagnoseStatic(s, dc);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  EXPECT_EQ(r.baseline_extra.at("window_scans"), 8.0);
  EXPECT_EQ(r.primary_cause, toString(Effect::mixed_pixels)) << r.decision;
}

TEST(DiagnoseStatic, ADriftIsSimulatedOnTheFitsConventionFromItsSceneKeys) {
  // The fit centres the drift on the mean scan; the scene keys that simulate it say so
  // (range_drift_reference_scan) instead of moving alpha_0, and the extended simulation, which
  // uses them, comes closer to the data than the baseline's.
  RangeEffects fx;
  fx.range_drift_m_per_scan = 2e-4;
  const int scans = 150;
  DiagnoseConfig dc;
  dc.replicas = 9;
  const auto r = diagnoseStatic(staticRoom(fx, squared(0.0015), 7, scans), dc);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  ASSERT_EQ(r.primary_cause, toString(Effect::range_drift)) << r.decision;
  ASSERT_TRUE(r.scene_keys.count("sensor.effects.range_drift_reference_scan"));
  EXPECT_NEAR(r.scene_keys.at("sensor.effects.range_drift_reference_scan"), (scans - 1) / 2.0, 1.0);
  EXPECT_NEAR(r.scene_keys.at("sensor.effects.range_drift_m_per_scan"), 2e-4, 4e-5);
  EXPECT_LT(r.closeness_extended.variance_ratio_median_abs_log, r.closeness_baseline.variance_ratio_median_abs_log);
}

/// The beams of a 20-degree sector (sensor frame, 10 to 29 degrees) of the room at 0.6 of their range in the scans
/// `moved` says: an object standing in front of the walls there.
diagnosis::StaticScans roomWithObject(std::uint64_t seed, const std::function<bool(std::uint32_t)>& moved) {
  diagnosis::StaticScans s = staticRoom({}, squared(0.0015), seed);
  for (auto& r : s.readings)
    if (r.angle_rad > deg2rad(9.5) && r.angle_rad < deg2rad(29.5) && moved(r.scan)) r.range_m *= 0.6;
  return s;
}

constexpr double kSectorBeams = 20.0;  // the 1-degree beams from 10 to 29 degrees

TEST(DiagnoseStatic, BeamsThatSawAnObjectCarriedAwayAreLeftOutAndTheRoomStaysClean) {
  // A box stood in front of the walls for the first third of the recording, then was carried
  // away (the forklift recordings: reflectors and people move while the sensor stands still).
  // The sensor did not move: no windows; the sector's beams are left out, and the rest of the
  // room is the clean room it is.
  DiagnoseConfig dc;
  dc.replicas = 9;
  const auto r = diagnoseStatic(roomWithObject(3, [](std::uint32_t scan) { return scan < 50; }), dc);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  EXPECT_EQ(r.baseline_extra.at("window_scans"), 0.0);
  // Every beam of the sector; a few beams' readings fall in two bins (their angles, computed
  // from float coordinates, round apart), hence the margin of six.
  EXPECT_GE(r.baseline_extra.at("scene_changed_bins"), kSectorBeams);
  EXPECT_LE(r.baseline_extra.at("scene_changed_bins"), kSectorBeams + 6.0);
  EXPECT_EQ(r.primary_cause, cause::kNone) << r.decision;
  EXPECT_NEAR(r.baseline.noise.sigma_e, 0.0015, 0.0002);
}

TEST(DiagnoseStatic, ReadingsOffTheirBeamAtRandomScansAreNotASceneChange) {
  // The same sector's beams at 0.6 of their range in a third of the scans drawn at random (the
  // test's own stream): off readings scattered in time are the sensor's (mixed pixels, tails),
  // not an object carried in or out, and stay in the data.
  for (std::uint64_t seed : {11u, 12u}) {
    SCOPED_TRACE(seed);
    auto rng = makeRng(seed, 5);
    std::vector<bool> off(150);
    for (std::size_t t = 0; t < off.size(); ++t) off[t] = std::uniform_real_distribution<double>(0.0, 1.0)(rng) < 1.0 / 3.0;
    DiagnoseConfig dc;
    dc.replicas = 5;
    dc.candidates = {Effect::mixed_pixels};
    const auto r = diagnoseStatic(roomWithObject(3, [&](std::uint32_t scan) { return off[scan]; }), dc);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    EXPECT_EQ(r.baseline_extra.at("scene_changed_bins"), 0.0);
  }
}

TEST(DiagnoseStatic, ProgressHearsEveryStepAndChangesNothing) {
  DiagnoseConfig dc;
  dc.replicas = 5;
  const diagnosis::StaticScans s = staticRoom({}, squared(0.0015), 3, 60);
  const auto quiet = diagnoseStatic(s, dc);
  std::vector<std::string> stages;
  std::size_t replicas_done = 0;
  dc.progress = [&](const std::string& stage, std::size_t done, std::size_t total) {
    if (stages.empty() || stages.back() != stage) stages.push_back(stage);
    if (stage == "bootstrap replicas") {
      EXPECT_EQ(total, 5u);
      replicas_done = std::max(replicas_done, done);
    }
    EXPECT_TRUE(total == 0 || done <= total) << stage;
  };
  const auto heard = diagnoseStatic(s, dc);
  EXPECT_EQ(stages, (std::vector<std::string>{"baseline fit", "bootstrap replicas", "held-out fits", "candidate tests",
                                              "extended model"}));
  EXPECT_EQ(replicas_done, 5u);
  EXPECT_EQ(heard.primary_cause, quiet.primary_cause);
  EXPECT_EQ(heard.baseline_heldout_nats_per_point, quiet.baseline_heldout_nats_per_point);
  EXPECT_EQ(heard.gain_heldout_nats_per_point, quiet.gain_heldout_nats_per_point);
}

/// Static clean-room runs over many seeds (LIDARCAL_STATIC_CLEAN_SEEDS; the long run registers 20):
/// how often clean data get a cause. Skipped when the variable is unset.
TEST(DiagnoseStatic, CleanRoomFalsePositiveRateOverSeeds) {
  const char* env = std::getenv("LIDARCAL_STATIC_CLEAN_SEEDS");
  const int n = env && *env ? std::atoi(env) : 0;
  if (n <= 0) GTEST_SKIP() << "set LIDARCAL_STATIC_CLEAN_SEEDS (ctest -L long runs 20)";
  int named = 0;
  std::string which;
  for (int seed = 101; seed < 101 + n; ++seed) {
    DiagnoseConfig dc;
    dc.seed = static_cast<std::uint64_t>(seed);
    const auto r = diagnoseStatic(staticRoom({}, squared(0.0015), static_cast<std::uint64_t>(seed)), dc);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    if (r.primary_cause != cause::kNone) {
      ++named;
      which += " seed " + std::to_string(seed) + ": " + r.primary_cause + ";";
    }
  }
  std::printf("static clean room: a cause named in %d of %d seeds;%s\n", named, n, which.c_str());
  // Holm at alpha = 0.01 over the candidates: at most 1 % of clean recordings should get a cause.
  // Allowance: at most 1 in 20 (a method at exactly 1 % exceeds it with probability 1.7 %).
  EXPECT_LE(named, std::max(1, n / 20)) << which;
}

/// One pose in front of `walls` (and `poles`) only: the room's sensor with 0.25-degree beams.
StaticScans sceneOf(std::vector<Segment> walls, std::vector<Cylinder> poles, std::uint64_t seed) {
  Scene s = test::staticRoomScene({}, squared(0.0015), 60, 0.0);
  s.sensor.beams = 1440;
  s.sensor.angle_increment_rad = deg2rad(0.25);
  s.walls = std::move(walls);
  s.clutter = std::move(poles);
  return test::sceneScans(s, seed);
}

TEST(DiagnoseStatic, OneTargetAloneIsRefusedAndOneLongWallIsNot) {
  // Scans masked to one target, as the Hokuyo range sweep is (a reflector, nothing else), or a
  // short board: enough beams return, but over a few degrees, with no spread in range or
  // incidence to read an effect off.
  DiagnoseConfig dc;
  dc.replicas = 5;
  for (const auto& [what, scans] :
       {std::pair{"a pole 0.9 m away", sceneOf({}, {{1.0, 0.3, 0.045}}, 3)},
        std::pair{"a 0.2 m board 1.7 m away", sceneOf({{2.0, -0.1, 2.0, 0.1}}, {}, 4)}}) {
    SCOPED_TRACE(what);
    const auto r = diagnoseStatic(scans, dc);
    EXPECT_STREQ(r.status.name(), "too_few_walls") << r.status.message << " cause " << r.primary_cause;
    EXPECT_NE(r.status.message.find("room"), std::string::npos) << r.status.message;  // says what to record
  }
  // One wall 1.7 m away across 120 degrees of the view is enough.
  const auto wall = diagnoseStatic(sceneOf({{2.0, -3.0, 2.0, 3.0}}, {}, 5), dc);
  EXPECT_TRUE(wall.status.ok()) << wall.status.name() << ": " << wall.status.message;
  EXPECT_EQ(wall.landmarks, 1u);
}

TEST(DiagnoseStatic, TooFewScansGiveAStatus) {
  const auto r = diagnoseStatic(staticRoom({}, squared(0.0015), 1, 3), DiagnoseConfig{});
  EXPECT_STREQ(r.status.name(), "too_few_scans");
  EXPECT_FALSE(r.status.message.empty());
}

// ---------------------------------------------------------------------------------------------
// Tails explained by covariates (diagnosis/tails.hpp).

/// Residuals drawn from the tail model itself: the EM recovers its parameters (oracle: the truth).
TEST(DiagnoseTails, EmRecoversTheContaminationModelFromItsOwnDraws) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    auto rng = makeRng(seed, 17);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    TailModel truth;
    truth.sigma_e = 0.002;
    truth.gamma = 1.0;
    truth.wide = 8.0;
    truth.beta = {-4.0, 3.0, 0.0, 0.0, 0.0};
    truth.spec.covariate[kTailEdge] = true;
    std::vector<TailBeam> beams(200);
    std::vector<TailReading> readings;
    for (std::size_t b = 0; b < beams.size(); ++b) {
      beams[b].log_range = std::log(1.0 + 3.0 * unit(rng));
      beams[b].log_sec_inc = -std::log(std::cos(deg2rad(70.0) * unit(rng)));
      beams[b].x = {b % 2 == 0 ? 1.0 : 0.0, beams[b].log_sec_inc, beams[b].log_range - 0.8, 0.0};
      for (int k = 0; k < 200; ++k) {
        const double s = truth.sigma(beams[b]) * (unit(rng) < truth.tailProbability(beams[b]) ? truth.wide : 1.0);
        readings.push_back({b, s * normal(rng), 1.0});
      }
    }
    TailSpec spec;
    spec.covariate = {true, true, true, false};
    spec.gamma = true;
    const TailModel m = fitTailModel(beams, readings, spec, 0.01, 1e-3, 1.0 / 12.0);
    EXPECT_TRUE(m.converged);
    EXPECT_NEAR(m.sigma_e, 0.002, 0.0001);
    EXPECT_NEAR(m.gamma, 1.0, 0.05);
    EXPECT_NEAR(m.wide, 8.0, 0.5);
    EXPECT_NEAR(m.beta[0], -4.0, 0.3);
    EXPECT_NEAR(m.beta[1 + kTailEdge], 3.0, 0.3);
    EXPECT_NEAR(m.beta[1 + kTailGrazing], 0.0, 0.3);  // covariates without effect stay near 0
    EXPECT_NEAR(m.beta[1 + kTailRange], 0.0, 0.3);
  }
}

/// Degenerate inputs: no readings, or every residual zero (a sensor that repeats itself): finite
/// parameters, no crash; no readings is reported as not converged.
TEST(DiagnoseTails, DegenerateInputsGiveFiniteParameters) {
  std::vector<TailBeam> beams(3);
  TailSpec spec;
  spec.covariate = {true, true, true, true};
  spec.kappa = spec.gamma = spec.mixed = true;
  const TailModel none = fitTailModel(beams, {}, spec, 0.01, 1e-3, 0.1);
  EXPECT_FALSE(none.converged);
  std::vector<TailReading> zeros;
  for (std::size_t b = 0; b < beams.size(); ++b)
    for (int k = 0; k < 20; ++k) zeros.push_back({b, 0.0, 1.0});
  const TailModel flat = fitTailModel(beams, zeros, spec, 0.01, 1e-3, 0.1);
  for (double v : {flat.sigma_e, flat.kappa, flat.gamma, flat.wide, flat.mixed, flat.beta[0]}) EXPECT_TRUE(std::isfinite(v));
  EXPECT_TRUE(std::isfinite(flat.logDensity(beams[0], 0.001, 1.0, 1e-3, 0.1)));
}

/// Where the test puts the extra-wide errors, and what the diagnosis must say about them.
struct TailTruth {
  const char* name;
  test::TailWhere where;
  const char* effect;  ///< the physical cause to name
  const char* cls;     ///< the class of beams holding most of the tail readings
};

class StaticTails : public ::testing::TestWithParam<TailTruth> {};

/// Extra-wide errors (10 % of the readings of one class of beams, 5 cm) only at grazing incidence,
/// only at depth edges or only on a dark wall: named by the physical effect (not heavy_tails), the
/// tails put in that class. Four seeds the method was not tuned on; at least 3 right (a method
/// right 95 % of the time passes with probability 0.99).
TEST_P(StaticTails, DiagnoseNamesThePhysicalCauseAndTheBeamsThatCarryTheTails) {
  const TailTruth& c = GetParam();
  int right = 0;
  std::string log;
  for (const std::uint64_t seed : unreadSeeds(nameTag(c.effect) + 301, 4)) {
    DiagnoseConfig dc;
    dc.replicas = 5;
    dc.seed = seed;
    const auto r = diagnoseStatic(test::staticRoomWithTails(c.where, 0.10, 0.05, seed), dc);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    ASSERT_TRUE(r.tails.fitted) << r.tails.note;
    const std::string top = test::dominantTailClass(r.tails);
    right += r.primary_cause == c.effect && r.tails.cause == c.effect && top == c.cls;
    log += " seed " + std::to_string(seed) + ": " + r.primary_cause + ", tails " + r.tails.cause + ", class " + top + ";";
  }
  std::printf("%s:%s\n", c.name, log.c_str());
  EXPECT_GE(right, 3) << log;
}

INSTANTIATE_TEST_SUITE_P(Room, StaticTails,
                         ::testing::Values(TailTruth{"grazing", test::TailWhere::grazing, "incidence_noise", "grazing"},
                                           TailTruth{"edge", test::TailWhere::edge, "mixed_pixels", "edge"},
                                           TailTruth{"dark", test::TailWhere::dark, "dark_surface", "dark"}),
                         [](const auto& p) { return std::string(p.param.name); });

/// The tail study gives the same numbers, to the last bit, when run again with the same seed.
TEST(DiagnoseStatic, TailStudyIsDeterministic) {
  DiagnoseConfig dc;
  dc.replicas = 5;
  const StaticScans s = test::staticRoomWithTails(test::TailWhere::edge, 0.10, 0.05, 331);
  const auto a = diagnoseStatic(s, dc), b = diagnoseStatic(s, dc);
  ASSERT_TRUE(a.tails.fitted);
  EXPECT_EQ(a.primary_cause, b.primary_cause);
  EXPECT_EQ(a.tails.model, b.tails.model);
  EXPECT_EQ(a.tails.robust, b.tails.robust);
  EXPECT_EQ(a.tails.tail_readings_by_class, b.tails.tail_readings_by_class);
  ASSERT_EQ(a.tails.covariates.size(), b.tails.covariates.size());
  for (std::size_t k = 0; k < a.tails.covariates.size(); ++k)
    EXPECT_EQ(a.tails.covariates[k].unique_gain_nats_per_point, b.tails.covariates[k].unique_gain_nats_per_point);
  ASSERT_EQ(a.tails.top_beams.size(), b.tails.top_beams.size());
  for (std::size_t k = 0; k < a.tails.top_beams.size(); ++k)
    EXPECT_EQ(a.tails.top_beams[k].bearing_rad, b.tails.top_beams[k].bearing_rad);
}

/// Mixed pixels at 2-10 % of the edge readings (a fraction drawn per seed): the readings between
/// the two surfaces are tails on the edge beams, so mixed_pixels is named (by its own candidate, or
/// from the tails' edge covariate). Four seeds, at least 3. diagnoseStatic on staticRoom() with
/// `fx`, simulated and diagnosed with `seed`, 5 replicas.
DiagnosisResult diagnoseRoomAtSeed(const RangeEffects& fx, std::uint64_t seed) {
  DiagnoseConfig dc;
  dc.replicas = 5;
  dc.seed = seed;
  return diagnoseStatic(staticRoom(fx, squared(0.0015), seed), dc);
}

class ReadingGrid : public ::testing::TestWithParam<double> {};

TEST_P(ReadingGrid, ReadingsRoundedToItAreNamedQuantisation) {
  // Readings rounded to 2, 5 or 10 mm under noise of 3-50 mm (the room at 1.5-6 m). Every model is
  // scored on the readings spread uniformly over their grid cells, where the rounded model (a
  // normal cell probability over q) is the true one; a continuous model scored at the grid points,
  // or a variance floor, misses most 5 and 10 mm grids (docs/results/static-diagnosis.md). Four
  // rooms whose seeds come from a seed this test does not read (the method was developed on seeds
  // 101-130), at least 3 named.
  const double grid = GetParam();
  int right = 0;
  std::string log;
  for (const std::uint64_t seed : unreadSeeds(static_cast<std::uint64_t>(grid * 1e4), 4)) {
    RangeEffects fx;
    fx.range_resolution_m = grid;
    const auto r = diagnoseRoomAtSeed(fx, seed);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    right += names(r.primary_cause, Effect::quantisation);
    log += " seed " + std::to_string(seed) + ": " + r.primary_cause + ";";
  }
  std::printf("grid %.3f m:%s\n", grid, log.c_str());
  EXPECT_GE(right, 3) << "grid " << grid << ":" << log;
}

INSTANTIATE_TEST_SUITE_P(Room, ReadingGrid, ::testing::Values(0.002, 0.005, 0.010), [](const auto& grid_info) {
  return "mm" + std::to_string(static_cast<int>(std::lround(grid_info.param * 1e3)));
});

TEST(DiagnoseStatic, MixedPixelsAtTwoToTenPercentOfEdgeReadingsAreNamed) {
  int right = 0;
  std::string log;
  for (const std::uint64_t seed : unreadSeeds(321, 4)) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto rng = makeRng(seed, 5);
    RangeEffects fx;
    fx.mixed_pixel_fraction = 0.02 + 0.08 * u(rng);
    const auto r = diagnoseRoomAtSeed(fx, seed);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    right += names(r.primary_cause, Effect::mixed_pixels);
    char buf[200];
    std::snprintf(buf, sizeof buf, " seed %d (fraction %.3f): %s, tails %s;", static_cast<int>(seed), fx.mixed_pixel_fraction,
                  r.primary_cause.c_str(), r.tails.cause.c_str());
    log += buf;
  }
  std::printf("mixed pixels:%s\n", log.c_str());
  EXPECT_GE(right, 3) << log;
}

/// Tails everywhere (5 % of all readings 5 cm off) over a noise growing as (1 / cos phi)^1: the
/// incidence exponent fitted under the contamination comes out near 1 (under the Gaussian
/// likelihood 0.73-0.88 on these seeds), and incidence_noise is named.
TEST(DiagnoseStatic, IncidenceExponentIsRecoveredUnderContamination) {
  RangeEffects fx;
  fx.incidence_noise_exponent = 1.0;
  for (std::uint64_t seed = 311; seed < 314; ++seed) {
    SCOPED_TRACE(seed);
    DiagnoseConfig dc;
    dc.replicas = 5;
    dc.seed = seed;
    const auto r = diagnoseStatic(test::staticRoomWithTails(test::TailWhere::everywhere, 0.05, 0.05, seed, fx), dc);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    ASSERT_TRUE(r.tails.fitted) << r.tails.note;
    const double robust = r.tails.robust.at("incidence_noise_exponent");
    double gaussian = std::numeric_limits<double>::quiet_NaN();
    for (const auto& k : r.candidates)
      if (k.effect == Effect::incidence_noise) gaussian = k.estimates.at("incidence_noise_exponent");
    std::printf("seed %d: incidence exponent %.3f under the contamination, %.3f under the Gaussian; named %s; robust gains: "
                "gamma %.4f +- %.4f, kappa %.4f +- %.4f\n",
                static_cast<int>(seed), robust, gaussian, r.primary_cause.c_str(), r.tails.robust.at("incidence_noise_exponent_gain"),
                r.tails.robust.at("incidence_noise_exponent_gain_se"), r.tails.robust.at("noise_exponent_gain"),
                r.tails.robust.at("noise_exponent_gain_se"));
    EXPECT_NEAR(robust, 1.0, 0.15);
    // The Gaussian ranking, dominated by the tails, puts a range law first; ranked beside the
    // contamination the incidence noise comes first.
    EXPECT_EQ(r.primary_cause, "incidence_noise") << r.decision << " tails significant " << r.tails.significant << " p " << r.tails.p_value;
    EXPECT_GT(r.tails.robust.at("incidence_noise_exponent_gain"), 0.0);
  }
}

/// A noise law that grows on dark surfaces, sigma times (I_ref / I)^delta, in a room whose six walls
/// and pillar return intensities 20-250 (shuffled over the surfaces per room) and delta from
/// 0.2 to 1, both drawn from seeds the test does not read: dark_surface is named, its exponent
/// recovered and its reference the intensity of the median beam's surface.
struct DarkRoom {
  test::StaticCase c;
  DiagnosisResult r;
};

/// The room with its surfaces' intensities (test::roomIntensities) shuffled and a dark-surface
/// exponent drawn from [lo, hi], both from `seed`, Student-t noise of `dof` degrees of freedom when
/// dof > 0; diagnosed with `seed` and 5 replicas.
DarkRoom diagnoseDarkRoom(std::uint64_t seed, double lo, double hi, double dof) {
  auto rng = makeRng(seed, 9);
  DarkRoom d{test::StaticCase{"dark", "dark_surface", {}, RangeEffects{}}, {}};
  d.c.intensities = test::roomIntensities();
  std::shuffle(d.c.intensities.begin(), d.c.intensities.end(), rng);
  d.c.fx.dark_noise_exponent = std::uniform_real_distribution<double>(lo, hi)(rng);
  d.c.fx.dark_reference_intensity = 90.0;
  d.c.fx.noise_student_dof = dof;
  DiagnoseConfig dc;
  dc.replicas = 5;
  dc.seed = seed;
  d.r = diagnoseStatic(test::staticRoom(d.c, seed), dc);
  return d;
}

TEST(DiagnoseStatic, ADarkSurfaceNoiseLawIsNamedAndItsExponentRecovered) {
  for (const std::uint64_t seed : unreadSeeds(nameTag("static dark surface"), 2)) {
    SCOPED_TRACE(seed);
    const auto [c, r] = diagnoseDarkRoom(seed, 0.2, 1.0, 0.0);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    EXPECT_EQ(r.primary_cause, "dark_surface") << r.decision;
    const CandidateResult* k = nullptr;
    for (const auto& x : r.candidates)
      if (x.effect == Effect::dark_surface) k = &x;
    ASSERT_NE(k, nullptr);
    ASSERT_TRUE(k->applicable) << k->note;
    EXPECT_NEAR(k->estimates.at("dark_noise_exponent"), c.fx.dark_noise_exponent, 0.05);
    // The reference is the median beam's intensity: that of one of the surfaces (the scale
    // sigma_e takes up the difference from the simulator's reference).
    const double ref = k->estimates.at("dark_reference_intensity");
    EXPECT_TRUE(std::any_of(c.intensities.begin(), c.intensities.end(), [ref](double v) { return std::abs(ref / v - 1.0) < 1e-6; }))
        << ref;
    EXPECT_TRUE(r.scene_keys.count("sensor.effects.dark_noise_exponent"));
  }
}

/// The dark-surface law under Student-t noise (3 degrees of freedom, every reading): fitted beside
/// the pooled contamination its exponent is not dragged by the tails, and dark_surface is named
/// (delta from 0.3 to 1 and the surfaces' intensities shuffled, from seeds the test does not read).
TEST(DiagnoseStatic, ADarkSurfaceLawUnderHeavyTailsIsNamedBesideTheContamination) {
  for (const std::uint64_t seed : unreadSeeds(nameTag("static dark surface under tails"), 2)) {
    SCOPED_TRACE(seed);
    const auto [c, r] = diagnoseDarkRoom(seed, 0.3, 1.0, 3.0);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    ASSERT_TRUE(r.tails.robust.count("dark_noise_exponent"));
    const double robust = r.tails.robust.at("dark_noise_exponent");
    std::printf("seed %llu: delta %.3f, beside the contamination %.3f; named %s\n", static_cast<unsigned long long>(seed),
                c.fx.dark_noise_exponent, robust, r.primary_cause.c_str());
    EXPECT_NEAR(robust, c.fx.dark_noise_exponent, 0.15);
    EXPECT_EQ(r.primary_cause, "dark_surface") << r.decision;
  }
}

/// A time-of-flight sensor without intensity compensation: every return's intensity falls as
/// 1 / range^2, so darkness and range say the same. With the noise law hidden (sigma as f^0.5) the
/// dark-surface candidate is not identifiable (and says why), and dark_surface is not named.
TEST(DiagnoseStatic, IntensityThatFollowsTheRangeCannotNameADarkSurface) {
  const std::uint64_t seed = unreadSeeds(nameTag("intensity follows range"), 1).front();
  test::StaticCase c{"range law", "range_noise_law", {}, RangeEffects{}};
  c.noise.kind = NoiseKind::power;
  c.noise.exponent = 0.5;
  c.noise.sigma_e = 0.0015 * std::pow(3.0, 1.5);
  auto scans = test::staticRoom(c, seed);
  scans.has_intensity = true;
  for (auto& rd : scans.readings) rd.intensity = 1000.0 / (rd.range_m * rd.range_m);
  DiagnoseConfig dc;
  dc.replicas = 5;
  dc.seed = seed;
  const auto r = diagnoseStatic(scans, dc);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  EXPECT_NE(r.primary_cause, "dark_surface") << r.decision;
  EXPECT_TRUE(r.primary_cause == "range_noise_law" || r.primary_cause == "not_identifiable") << r.primary_cause << ": " << r.decision;
  for (const auto& k : r.candidates)
    if (k.effect == Effect::dark_surface) {
      EXPECT_FALSE(k.identifiable);
      EXPECT_NE(k.note.find("follows the range"), std::string::npos) << k.note;
      EXPECT_GT(k.estimates.at("darkness_range_correlation"), 0.95);
    }
}

/// When the contamination a cause is named beside holds most of the readings (70 % of all readings
/// 5 cm off, noise growing as (1 / cos phi)^1), the decision says that what is fitted beside it
/// describes those readings more than the sensor; with 5 % it does not.
TEST(DiagnoseStatic, ACauseNamedBesideAContaminationOfMostReadingsComesWithACaution) {
  RangeEffects fx;
  fx.incidence_noise_exponent = 1.0;
  const std::uint64_t seed = unreadSeeds(nameTag("contamination of most readings"), 1).front();
  for (const double rate : {0.05, 0.7}) {
    SCOPED_TRACE(rate);
    DiagnoseConfig dc;
    dc.replicas = 5;
    dc.seed = seed;
    const auto r = diagnoseStatic(test::staticRoomWithTails(test::TailWhere::everywhere, rate, 0.05, seed, fx), dc);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    ASSERT_TRUE(r.tails.fitted) << r.tails.note;
    std::printf("contamination %.2f: pooled fraction %.2f, named %s\n", rate, r.tails.pooled_fraction, r.primary_cause.c_str());
    const bool caution = r.decision.find("caution") != std::string::npos;
    EXPECT_EQ(caution, r.tails.pooled_fraction > 0.5) << r.decision;
    if (rate > 0.5) EXPECT_TRUE(caution) << r.primary_cause << ": " << r.decision;
    else EXPECT_FALSE(caution) << r.decision;
  }
}

/// Without intensities, or with one value on every reading (the RPLIDAR's 47), a dark surface
/// cannot show: the candidate is not applicable and says what to record.
TEST(DiagnoseStatic, DarkSurfaceIsNotApplicableWithoutVaryingIntensities) {
  for (const bool constant : {false, true}) {
    SCOPED_TRACE(constant);
    test::StaticCase c{"clean", "none", {}, RangeEffects{}};
    if (constant) c.intensities.assign(7, 47.0);
    DiagnoseConfig dc;
    dc.replicas = 5;
    dc.seed = 5;
    const auto r = diagnoseStatic(test::staticRoom(c, 5), dc);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    bool seen = false;
    for (const auto& k : r.candidates)
      if (k.effect == Effect::dark_surface) {
        seen = true;
        EXPECT_FALSE(k.applicable);
        EXPECT_NE(k.note.find("intensit"), std::string::npos) << k.note;
      }
    EXPECT_TRUE(seen);
    EXPECT_NE(r.primary_cause, "dark_surface");
  }
}

}  // namespace
}  // namespace lidarcal::diagnosis


