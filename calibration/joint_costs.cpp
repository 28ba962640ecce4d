// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/joint_costs.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lidarcal::calibration::joint {
namespace {

template <int N>
ceres::CostFunction* makeBeamCost(double angle, double y, double inv_sigma) {
  return new BeamRangeAnalyticCost<N>(angle, y, inv_sigma);
}

template <int N>
ceres::CostFunction* makeKnownRangeCost(const KnownRange& k, double inv_sigma) {
  return new ceres::AutoDiffCostFunction<KnownRangeCost<N>, 1, N, 1>(
      new KnownRangeCost<N>{&k, inv_sigma});
}

template <int N>
ceres::CostFunction* makeEffectCost(double angle, double y, double inv_sigma, double t_rel) {
  return new ceres::AutoDiffCostFunction<EffectBeamCost<N>, 1, 3, 2, 1, N, 1, 3>(
      new EffectBeamCost<N>{angle, y, inv_sigma, t_rel});
}

}  // namespace

ceres::CostFunction* beamCost(int order, double angle, double y, double inv_sigma) {
  switch (order + 1) {
    case 2:
      return makeBeamCost<2>(angle, y, inv_sigma);
    case 3:
      return makeBeamCost<3>(angle, y, inv_sigma);
    case 4:
      return makeBeamCost<4>(angle, y, inv_sigma);
    case 5:
      return makeBeamCost<5>(angle, y, inv_sigma);
    case 6:
      return makeBeamCost<6>(angle, y, inv_sigma);
    case 7:
      return makeBeamCost<7>(angle, y, inv_sigma);
    default:
      throw std::invalid_argument("refineJoint: order must be 1..6");
  }
}

ceres::CostFunction* effectCost(int order, double angle, double y, double inv_sigma, double t_rel) {
  switch (order + 1) {
    case 2:
      return makeEffectCost<2>(angle, y, inv_sigma, t_rel);
    case 3:
      return makeEffectCost<3>(angle, y, inv_sigma, t_rel);
    case 4:
      return makeEffectCost<4>(angle, y, inv_sigma, t_rel);
    case 5:
      return makeEffectCost<5>(angle, y, inv_sigma, t_rel);
    case 6:
      return makeEffectCost<6>(angle, y, inv_sigma, t_rel);
    case 7:
      return makeEffectCost<7>(angle, y, inv_sigma, t_rel);
    default:
      throw std::invalid_argument("refineJoint: order must be 1..6");
  }
}

ceres::CostFunction* knownRangeCost(int order, const KnownRange& k, double inv_sigma) {
  switch (order + 1) {
    case 2:
      return makeKnownRangeCost<2>(k, inv_sigma);
    case 3:
      return makeKnownRangeCost<3>(k, inv_sigma);
    case 4:
      return makeKnownRangeCost<4>(k, inv_sigma);
    case 5:
      return makeKnownRangeCost<5>(k, inv_sigma);
    case 6:
      return makeKnownRangeCost<6>(k, inv_sigma);
    case 7:
      return makeKnownRangeCost<7>(k, inv_sigma);
    default:
      throw std::invalid_argument("refineJoint: order must be 1..6");
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

double noiseShape(const NoiseModel& n, const BiasPolynomial& f, const NoiseCovariates& c) {
  const double d = c.d;
  double h = 1.0;
  switch (n.kind) {
    case NoiseKind::squared:
      h = f(d) * f(d);
      break;
    case NoiseKind::power:
      h = std::pow(std::abs(f(d)), n.exponent);
      break;
    case NoiseKind::polynomial: {
      NoiseModel unit = n;
      h = unit.stddev(d, f);
      break;
    }
    default:
      break;
  }
  return h * incidenceNoiseFactor(c.gamma, c.cos_inc) * darkNoiseFactor(c.delta, c.dark);
}
}  // namespace lidarcal::calibration::joint
