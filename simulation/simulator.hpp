// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Scan-level simulator: the robot stops along a straight line (Alhashimi et al. 2021 eqs. 7-8) or
// drives along a route (a pose per scan, odometry drifting as a random walk), the lidar sweeps its
// beams, each beam is ray-cast against the scene and its reading drawn from the range model
// (Alhashimi et al. 2021 eq. 3 or Alhashimi et al. 2016 eq. 1).
//
// Randomness: the stop poses come from stream 0 of the seed, scan i from stream i + 1, so any
// scan can be produced on its own (streaming, threads) with the same bytes.

#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "common/range_effects.hpp"
#include "common/range_model.hpp"
#include "common/scene.hpp"
#include "common/truth.hpp"
#include "io/pcd_scan.hpp"
#include "io/true_ranges.hpp"

namespace lidarcal::simulation {

/// A reading for true distance d: f(d) + sigma(d) * unit_normal (Alhashimi et al. 2021 eq. 3 /
/// Alhashimi et al. 2016 eq. 1).
double rangeReading(const RangeModel& model, double d_m, double unit_normal);

/// Where and when a beam met its surface: what the effects of common/range_effects.hpp depend on.
struct BeamContext {
  double cos_incidence = 1.0;  ///< cosine of the angle between the beam and the surface normal
  /// range offset of the surface hit (Cylinder/Segment::range_offset_m), metres
  double surface_offset_m = 0.0;
  std::size_t scan = 0;  ///< scan index in the sequence (drift)
  /// return intensity of the surface hit (0: none recorded; dark-surface noise)
  double intensity = 0.0;
};

/// Generator of the effects' own random numbers for scan `scan`: a stream apart from the
/// scan's, so that switching effects on leaves every other draw of the sequence unchanged.
std::mt19937_64 effectRng(std::uint64_t seed, std::size_t scan);

/// A reading with effects: f(d) + b_inc (1 - cos phi) + offset + c_drift t + sigma(d) (1/cos
/// phi)^gamma (I_ref/I)^delta e, quantised. e is `unit_normal`, or with a Student-t noise a
/// unit-variance t variate built from it and a chi-square draw from `effect_rng` (drawn only when
/// that effect is on). With every effect off this is rangeReading().
double effectReading(const RangeModel& model, const RangeEffects& effects, double d_m,
                     const BeamContext& beam, double unit_normal, std::mt19937_64& effect_rng);

/// Mixed pixel draw for one beam (two uniforms from `effect_rng` whenever the effect is on, so
/// the stream stays aligned): the distance the beam reads at, w d + (1 - w) d_background with
/// w ~ U(0, 1) when it is a mixed pixel, else d. `background_m` <= d (or NaN): no background, no
/// mix.
double mixedPixelDistance(const RangeEffects& effects, double d_m, double background_m,
                          std::mt19937_64& effect_rng);

/// Commanded and actual pose of every stop, and the scans that belong to it. Stop and go: seed
/// 000 eqs. 7-8. Driving: the true poses every speed_m_per_scan along the route, the commanded
/// ones the odometry's noisy steps chained from the start (common/scene.hpp, OdometryNoise); a
/// scan is taken at one pose (the motion during a sweep is not simulated).
std::vector<TruthStop> planStops(const Scene& scene, std::uint64_t seed);

/// The distances from the stops' true poses to the nearest point of each pole the sensor reaches
/// (inside its range window; occlusion ignored), [min, max] metres: the fitted range a calibration
/// of these stops would report. {range_min, range_max} when no pole is in reach.
std::pair<double, double> poleDistanceRange(const Scene& scene,
                                            const std::vector<TruthStop>& stops);

/// One simulated scan with the truth of each of its beams.
struct SimulatedScan {
  io::Scan scan;                     ///< points in the sensor frame, VIEWPOINT = commanded pose
  std::vector<io::TrueRange> truth;  ///< one row per beam
};

/// Simulates scan `scan_index` (taken at `stop`) of the sequence.
SimulatedScan simulateScan(const Scene& scene, const TruthStop& stop, std::size_t scan_index,
                           std::uint64_t seed);

/// Calls visit(k, scan) for every scan taken at `stops`, in order (stop k's scans in turn), each
/// simulated when it is visited, so a long sequence need not be held in memory.
void forEachScan(const Scene& scene, const std::vector<TruthStop>& stops, std::uint64_t seed,
                 const std::function<void(std::size_t stop, SimulatedScan&& scan)>& visit);

/// Every scan taken at the stops, in order, and the stop each was taken at.
struct SimulatedSequence {
  std::vector<SimulatedScan> scans;
  std::vector<std::size_t> stop_of_scan;  ///< index into the stops, one per scan
};

/// The whole sequence in memory: forEachScan, collected.
SimulatedSequence simulateSequence(const Scene& scene, const std::vector<TruthStop>& stops,
                                   std::uint64_t seed);

}  // namespace lidarcal::simulation
