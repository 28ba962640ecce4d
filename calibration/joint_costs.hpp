// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal to the joint refinement (joint_problem.cpp, joint_refinement.cpp): the Ceres
// residuals of one beam reading and of the pose priors, and the geometry of a beam at an
// estimate. The model they implement is documented in joint_refinement.hpp.

#include <cmath>

#include <ceres/ceres.h>

#include "calibration/joint_refinement.hpp"
#include "common/range_effects.hpp"

namespace lidarcal::calibration::joint {

/// Residual of one beam reading: (y - f(d(pose, centre, radius))) / sigma_i, N = order + 1.
template <int N>
struct BeamRangeCost {
  double angle_rad, y_m, inv_sigma;
  template <typename T>
  bool operator()(const T* pose, const T* centre, const T* radius, const T* alpha,
                  T* residual) const {
    const T a = pose[2] + T(angle_rad);
    const T d = rayCircleDistance(pose[0], pose[1], a, centre[0], centre[1], radius[0]);
    residual[0] = (T(y_m) - evaluatePolynomial<N>(alpha, d)) * T(inv_sigma);
    return true;
  }
};

/// BeamRangeCost with its derivatives written out (the same residual; the joint refinement's
/// most evaluated term: autodiff's 11-wide dual numbers took 70 % of a long log's solve). With
/// a = heading + beam angle, (c, s) = (cos a, sin a), (dx, dy) = centre - position:
///   along = dx c + dy s,  perp = dy c - dx s,  q = sqrt(r^2 - perp^2),  d = along - q
/// (d = along when the ray misses), so
///   dd = d(along) + (perp / q) d(perp) - (r / q) dr,
/// with d(along)/d(px, py, a, cx, cy) = (-c, -s, perp, c, s) and
///      d(perp)/d(px, py, a, cx, cy)  = (s, -c, -along, -s, c);
/// residual = (y - f(d)) w: its derivative is -w f'(d) dd, and -w d^k for alpha_k.
template <int N>
class BeamRangeAnalyticCost final : public ceres::SizedCostFunction<1, 3, 2, 1, N> {
 public:
  BeamRangeAnalyticCost(double angle_rad, double y_m, double inv_sigma)
      : angle_rad_(angle_rad), y_m_(y_m), inv_sigma_(inv_sigma) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* pose = parameters[0];
    const double* centre = parameters[1];
    const double r = parameters[2][0];
    const double* alpha = parameters[3];
    const double a = pose[2] + angle_rad_;
    const double c = std::cos(a), s = std::sin(a);
    const double dx = centre[0] - pose[0], dy = centre[1] - pose[1];
    const double along = dx * c + dy * s;
    const double perp = dy * c - dx * s;
    const double disc = r * r - perp * perp;
    const bool hit = disc > 0.0;
    const double q = hit ? std::sqrt(disc) : 0.0;
    const double d = hit ? along - q : along;
    residuals[0] = (y_m_ - evaluatePolynomial<N>(alpha, d)) * inv_sigma_;
    if (jacobians == nullptr) return true;
    // f'(d) by Horner's rule on the derivative's coefficients.
    double fp = 0.0;
    for (int k = N - 1; k >= 1; --k) fp = fp * d + k * alpha[k];
    const double g = -inv_sigma_ * fp;  // d(residual)/dd
    const double kp = hit ? perp / q : 0.0;
    const double kr = hit ? -r / q : 0.0;
    if (jacobians[0]) {
      jacobians[0][0] = g * (-c + kp * s);
      jacobians[0][1] = g * (-s - kp * c);
      jacobians[0][2] = g * (perp - kp * along);
    }
    if (jacobians[1]) {
      jacobians[1][0] = g * (c - kp * s);
      jacobians[1][1] = g * (s + kp * c);
    }
    if (jacobians[2]) jacobians[2][0] = g * kr;
    if (jacobians[3]) {
      double dk = 1.0;
      for (int k = 0; k < N; ++k, dk *= d) jacobians[3][k] = -inv_sigma_ * dk;
    }
    return true;
  }

 private:
  double angle_rad_, y_m_, inv_sigma_;
};

/// A measured target (KnownRange): its mean reading against the mean of f over its beams' true
/// distances (on a pole from its centre and the radius block; on a wall as given).
template <int N>
struct KnownRangeCost {
  const KnownRange* target;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* alpha, const T* radius, T* residual) const {
    T sum = T(0);
    double n = 0.0;
    for (const KnownRange::Beam& b : target->beams) {
      sum += T(b.count) *
             (T(b.mean_reading_m) - evaluatePolynomial<N>(alpha, target->distance(b, radius[0])));
      n += b.count;
    }
    residual[0] = sum / T(n) * T(inv_sigma);
    return true;
  }
};

/// The same with the effect terms in the mean: landmark offset o, and g = (drift c, zero-angle
/// offset a_0, incidence bias b); t_rel = t - t_ref.
template <int N>
struct EffectBeamCost {
  double angle_rad, y_m, inv_sigma, t_rel;
  template <typename T>
  bool operator()(const T* pose, const T* centre, const T* radius, const T* alpha, const T* offset,
                  const T* g, T* residual) const {
    using std::cos;
    using std::sin;
    using std::sqrt;
    const T a = pose[2] + T(angle_rad) + g[1];
    const T d = rayCircleDistance(pose[0], pose[1], a, centre[0], centre[1], radius[0]);
    const T perp = (centre[1] - pose[1]) * cos(a) - (centre[0] - pose[0]) * sin(a);
    const T u = perp / radius[0];
    const T cos_phi = sqrt(clampCosIncidenceSquared(T(1) - u * u));
    const T mean =
        expectedReading(evaluatePolynomial<N>(alpha, d), offset[0], g[0], T(t_rel), g[2], cos_phi);
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

/// Motion prior between consecutive stops a -> b: the commanded step (dx, dy, dpsi) against the
/// step from a to b in a's frame, its translation divided by 1 + s (odometry scale): the odometry
/// reports the true step shrunk by 1 + s plus its noise, so the residual is taken where the noise
/// is, on the commanded side. Scaling the commanded step instead (fitted - (1 + s) commanded)
/// regresses the true steps on noisy ones and dilutes the scale: a clean thin-pole drive's
/// odometry (3 mm per coordinate on 3 cm steps) gave s = -2 sigma^2 / L^2 = -2 %, named as a step
/// error on 4 of 40 clean drives once the odometry's noise was fitted
/// (docs/results/hidden-effects.md). With s = 0 both are the same.
struct MotionPriorCost {
  double dx, dy, dpsi, inv_t, inv_psi;
  template <typename T>
  bool operator()(const T* a, const T* b, const T* scale, T* residual) const {
    using std::cos;
    using std::sin;
    const T c = cos(a[2]), s = sin(a[2]);
    const T ex = b[0] - a[0], ey = b[1] - a[1];
    const T f = T(1) + scale[0];
    residual[0] = ((c * ex + s * ey) / f - T(dx)) * T(inv_t);
    residual[1] = ((c * ey - s * ex) / f - T(dy)) * T(inv_t);
    // Like the pose prior: dpsi is unwrapped next to the estimate when the residual is built.
    residual[2] = (b[2] - a[2] - T(dpsi)) * T(inv_psi);
    return true;
  }
};

/// MotionPriorCost with its derivatives written out (on long pose chains the automatic ones
/// were a sixth of `calibrate`'s time). With c, s the cosine and sine of a's heading and
/// (ex, ey) = b - a in the world frame, the step seen from a is (c ex + s ey, c ey - s ex):
/// r0 = (along / f - dx) inv_t, r1 = (across / f - dy) inv_t with f = 1 + scale:
///   d/d(a0, a1, a2) of r0 = (-c, -s, c ey - s ex) inv_t / f,  of r1 = (s, -c, -(c ex + s ey))
///   inv_t / f, d/d(b0, b1) of r0 = (c, s) inv_t / f,  of r1 = (-s, c) inv_t / f, d/d(scale) =
///   (-along, -across) inv_t / f^2,
/// and r2 = (b2 - a2 - dpsi) inv_psi moves with the headings alone.
class MotionPriorAnalyticCost final : public ceres::SizedCostFunction<3, 3, 3, 1> {
 public:
  explicit MotionPriorAnalyticCost(const MotionPriorCost& c) : c_(c) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* a = parameters[0];
    const double* b = parameters[1];
    const double f = 1.0 + parameters[2][0];
    const double c = std::cos(a[2]), s = std::sin(a[2]);
    const double ex = b[0] - a[0], ey = b[1] - a[1];
    const double along = c * ex + s * ey, across = c * ey - s * ex;
    residuals[0] = (along / f - c_.dx) * c_.inv_t;
    residuals[1] = (across / f - c_.dy) * c_.inv_t;
    residuals[2] = (b[2] - a[2] - c_.dpsi) * c_.inv_psi;
    if (jacobians == nullptr) return true;
    const double t = c_.inv_t / f, p = c_.inv_psi;
    if (double* j = jacobians[0]) {  // rows r0, r1, r2; columns a0, a1, a2
      j[0] = -c * t, j[1] = -s * t, j[2] = across * t;
      j[3] = s * t, j[4] = -c * t, j[5] = -along * t;
      j[6] = 0.0, j[7] = 0.0, j[8] = -p;
    }
    if (double* j = jacobians[1]) {
      j[0] = c * t, j[1] = s * t, j[2] = 0.0;
      j[3] = -s * t, j[4] = c * t, j[5] = 0.0;
      j[6] = 0.0, j[7] = 0.0, j[8] = p;
    }
    if (double* j = jacobians[2]) {
      j[0] = -along * t / f;
      j[1] = -across * t / f;
      j[2] = 0.0;
    }
    return true;
  }

 private:
  MotionPriorCost c_;
};

/// The residual of one reading (angle, reading y, 1 / sigma; t_rel the scan index minus the drift
/// reference): BeamRangeCost, or EffectBeamCost when a term of the mean is on. Throws
/// std::invalid_argument for an order outside 1..6.
ceres::CostFunction* beamCost(int order, double angle, double y, double inv_sigma);
ceres::CostFunction* effectCost(int order, double angle, double y, double inv_sigma, double t_rel);
ceres::CostFunction* knownRangeCost(int order, const KnownRange& k, double inv_sigma);

/// Geometry of a beam at the current estimate (pose x, y, heading; centre x, y): distance, cosine
/// of the incidence, lateral offset.
struct BeamGeometry {
  double d = 0.0, cos_inc = 1.0, lateral = 0.0;
};
BeamGeometry beamGeometry(const double* pose, double angle, const double* centre, double radius);

/// What a reading's noise depends on beyond its law: the distance, the incidence and the
/// darkness of its return, with the effects' exponents.
struct NoiseCovariates {
  double d = 0.0;        ///< distance, metres
  double cos_inc = 1.0;  ///< cosine of the incidence phi
  double gamma = 0.0;    ///< incidence exponent: (1 / cos phi)^gamma
  double dark = 0.0;     ///< darkness ln(I_ref / I) of the return
  double delta = 0.0;    ///< darkness exponent: (I_ref / I)^delta
};

/// Noise shape h (sigma = scale * h) of a reading: the law's dependence on d, the incidence and
/// the darkness.
double noiseShape(const NoiseModel& n, const BiasPolynomial& f, const NoiseCovariates& c);
/// The scale that multiplies the shape: sigma_e, or 1 for the polynomial law (its beta carry the
/// scale).
inline double noiseScale(const NoiseModel& n) {
  return n.kind == NoiseKind::polynomial ? 1.0 : n.sigma_e;
}
/// sigma_i = scale * h_i.
inline double readingSigma(const NoiseModel& n, const BiasPolynomial& f, const NoiseCovariates& c) {
  return noiseScale(n) * noiseShape(n, f, c);
}

}  // namespace lidarcal::calibration::joint
