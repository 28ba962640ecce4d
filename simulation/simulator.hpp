#pragma once
// Scan-level simulator: the robot stops along a straight line (seed 000 eqs. 7-8), the lidar
// sweeps its beams, each beam is ray-cast against the scene and its reading drawn from the
// range model (seed 000 eq. 3 or seed 004 eq. 1).
//
// Randomness: the stop poses come from stream 0 of the seed, scan i from stream i + 1, so any
// scan can be produced on its own (streaming, threads) with the same bytes.

#include <cstdint>
#include <random>
#include <vector>

#include "common/range_model.hpp"
#include "common/scene.hpp"
#include "common/truth.hpp"
#include "io/pcd_scan.hpp"
#include "io/true_ranges.hpp"

namespace lidarcal::simulation {

/// A reading for true distance d: f(d) + sigma(d) * unit_normal (seed 000 eq. 3 / seed 004 eq. 1).
double rangeReading(const RangeModel& model, double d_m, double unit_normal);

/// Commanded and actual pose of every stop, and the scans that belong to it.
std::vector<TruthStop> planStops(const Scene& scene, std::uint64_t seed);

/// One simulated scan with the truth of each of its beams.
struct SimulatedScan {
  io::Scan scan;                       ///< points in the sensor frame, VIEWPOINT = commanded pose
  std::vector<io::TrueRange> truth;    ///< one row per beam
};

/// Simulates scan `scan_index` (taken at `stop`) of the sequence.
SimulatedScan simulateScan(const Scene& scene, const TruthStop& stop, std::size_t scan_index, std::uint64_t seed);

}  // namespace lidarcal::simulation
