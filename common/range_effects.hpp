// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Effects beyond the seeds' range model (Alhashimi et al. 2021 A3-A4, Alhashimi et al. 2016 eq. 1),
// shared by the simulator and the calibration: what `lidarcal diagnose` looks for in measured data.
// Every effect is off by default (the seeds' model). Physical causes: docs/FORMAT.md ("Effects").
//
// A beam that hits a surface at true distance d with incidence phi (angle between the beam and
// the surface normal) in scan t reads
//   y = f(d) + ripple(d) + b_inc (1 - cos phi) + o_surface + c_drift (t - t_ref)
//       + sigma(d) (1 / cos phi)^gamma (I_ref / I)^delta e,
// with e a unit normal (or a unit-variance Student t with `noise_student_dof` degrees of freedom),
// rounded to a multiple of `range_resolution_m`; an edge beam (depth discontinuity next to it)
// is a mixed pixel with probability `mixed_pixel_fraction`: it reads a distance drawn uniformly
// between the foreground and the background. I is the return intensity of the surface (dark
// surfaces return little light: the spot's centroid, or the echo's timing, is found less
// precisely); the factor is 1 when the surface records no intensity.

#include <algorithm>
#include <cmath>

namespace lidarcal {

struct RangeEffects {
  /// gamma: the noise grows as (1 / cos phi)^gamma with the incidence phi. 0 = off.
  double incidence_noise_exponent = 0.0;
  /// b_inc: the reading grows by b_inc (1 - cos phi), metres (b_inc at grazing incidence). 0 = off.
  double incidence_bias_m = 0.0;
  /// c_drift: the reading grows by this much per scan (warm-up, temperature), metres per scan. 0 =
  /// off.
  double range_drift_m_per_scan = 0.0;
  /// t_ref: the scan index at which the drift term is zero. One convention for the simulator and
  /// every fit: a fit centres it on its mean scan (and reports it: model.json
  /// effects.range_drift_reference_scan), a scene's default 0 is the first scan.
  double range_drift_reference_scan = 0.0;
  /// Probability that a beam at a depth discontinuity returns a mixed reading, [0, 1]. 0 = off.
  double mixed_pixel_fraction = 0.0;
  /// Degrees of freedom of a Student-t range noise (heavy tails), > 2; 0 = Gaussian.
  double noise_student_dof = 0.0;
  /// Readings are rounded to a multiple of this, metres (quantisation). 0 = off.
  double range_resolution_m = 0.0;
  /// delta: the noise grows as (I_ref / I)^delta with the return intensity I (dark surfaces). 0 =
  /// off.
  double dark_noise_exponent = 0.0;
  /// I_ref: the intensity at which that factor is 1 (> 0; a fit takes the median intensity of its
  /// readings).
  double dark_reference_intensity = 1.0;
  /// A: the sensor's bias gains a ripple A sin(2 pi d / lambda + psi) over the true distance d,
  /// metres: a bias no low-order polynomial follows (rangeRipple). 0 = off.
  double ripple_amplitude_m = 0.0;
  /// lambda: the ripple's wavelength in the true distance, metres (> 0). Default 0.25.
  double ripple_wavelength_m = 0.25;
  /// psi: the ripple's phase at d = 0, radians. Default 0.
  double ripple_phase_rad = 0.0;

  /// Whether any effect is on.
  bool any() const {
    return incidence_noise_exponent != 0.0 || incidence_bias_m != 0.0 ||
           range_drift_m_per_scan != 0.0 || mixed_pixel_fraction != 0.0 ||
           noise_student_dof != 0.0 || range_resolution_m != 0.0 || dark_noise_exponent != 0.0 ||
           ripple_amplitude_m != 0.0;
  }
};

/// ln(I_ref / I): how much darker than the reference a return of intensity I is; 0 when either
/// is not a positive number (no intensity recorded).
inline double darkness(double intensity, double reference) {
  return intensity > 0.0 && reference > 0.0 && std::isfinite(intensity) && std::isfinite(reference)
             ? std::log(reference / intensity)
             : 0.0;
}

/// (I_ref / I)^delta = exp(delta ln(I_ref / I)): the factor on the noise standard deviation.
inline double darkNoiseFactor(double delta, double darkness_ln) {
  return delta == 0.0 ? 1.0 : std::exp(delta * darkness_ln);
}

/// The ripple of the sensor's bias at true distance d, metres: A sin(2 pi d / lambda + psi)
/// (0 when off). Part of the sensor's mean reading f(d) + ripple(d) in the simulator; no fit
/// models it, so what it leaves is model discrepancy (calibration/discrepancy.hpp).
inline double rangeRipple(const RangeEffects& fx, double d_m) {
  if (fx.ripple_amplitude_m == 0.0) return 0.0;
  constexpr double kTwoPi = 6.283185307179586;
  return fx.ripple_amplitude_m *
         std::sin(kTwoPi * d_m / fx.ripple_wavelength_m + fx.ripple_phase_rad);
}

/// cos phi kept away from 0: grazing beams are treated as at 87 degrees.
inline double clampCosIncidence(double cos_phi) { return std::clamp(std::abs(cos_phi), 0.05, 1.0); }

/// (1 / cos phi)^gamma: the factor on the noise standard deviation.
inline double incidenceNoiseFactor(double gamma, double cos_phi) {
  return gamma == 0.0 ? 1.0 : std::pow(1.0 / clampCosIncidence(cos_phi), gamma);
}

/// The mean reading of a beam (the equation at the top of this file without the noise):
/// f(d) + o + c t + b (1 - cos phi), f_d = f(d), o the surface offset, c the drift per scan,
/// t the scan index minus the drift's reference scan t_ref
/// (RangeEffects::range_drift_reference_scan), b the incidence bias, cos_phi the clamped cosine of
/// the incidence. The one expression of it, for the simulator, the Ceres residuals (T a jet) and
/// the evaluation; the terms are summed in this order everywhere.
template <typename T>
T expectedReading(const T& f_d, const T& offset, const T& drift_per_scan, const T& t,
                  const T& incidence_bias, const T& cos_phi) {
  return f_d + offset + drift_per_scan * t + incidence_bias * (T(1) - cos_phi);
}

/// cos^2 phi kept at or above 0.05^2 (clampCosIncidence for a squared cosine, any scalar type).
template <typename T>
T clampCosIncidenceSquared(const T& cos2_phi) {
  return cos2_phi < T(0.0025) ? T(0.0025) : cos2_phi;
}

/// Rounds a reading to the sensor's resolution (no rounding for resolution 0).
inline double quantise(double y_m, double resolution_m) {
  return resolution_m > 0.0 ? resolution_m * std::round(y_m / resolution_m) : y_m;
}

}  // namespace lidarcal
