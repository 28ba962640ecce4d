// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Repeated scans from one pose as direction bins: a beam over the scans (or over a window of
// scans when the sensor moved), its location fitted on any subset of the scans, and the bins'
// intensities as darkness. Internal to the diagnosis library (diagnosis/static_scene/).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/stats_util.hpp"
#include "diagnosis/static_scene.hpp"

namespace lidarcal::diagnosis::static_scene {

// ---------------------------------------------------------------------------------------------
// Direction bins: a beam over the scans.

struct Bin {
  int window = 0;      ///< window of scans it belongs to (0 when the whole recording is one pose)
  double angle = 0.0;  ///< mean angle of its readings
  std::vector<std::size_t> idx;  ///< its readings
  bool slope = false;            ///< the angle varies within the bin (irregular beam grids)
  int wall = -1;                 ///< wall line it lies on, -1 none
  bool edge = false;             ///< next to a depth discontinuity
  double near = 0.0, far = 0.0;  ///< at an edge: the depths on both sides
  double cos_inc = 1.0;          ///< cosine of the incidence (1 when unknown)
  bool inc_known = false;
  double intensity = kNaN;  ///< geometric mean intensity of its readings (NaN: none recorded)
  /// darkness ln(I_median / I) against the median bin's intensity (0: none recorded)
  double dark = 0.0;
};

/// Per-bin location fitted on a subset of the scans.
struct BinFit {
  double m = 0.0;              ///< mean reading at the bin's mean angle (and mean scan), metres
  double g = 0.0;              ///< trend in angle (irregular grids), metres per radian
  double abar = 0.0;           ///< mean angle of the readings fitted, radians
  double med = 0.0;            ///< median reading (after the drift), metres
  double s2 = 0.0;             ///< residual variance about the location, m^2
  double h = 0.0, tbar = 0.0;  ///< time trend (windows: the sensor creeping), metres per scan
  double n = 0.0;              ///< readings fitted (0: too few, no fit)
  /// Location of a reading at angle a in scan t.
  double at(double a, double t) const { return m + g * (a - abar) + h * (t - tbar); }
};

/// Readings in direction bins, with what the models need of them.
struct BinnedReadings {
  std::vector<double> a, y, t;  ///< each reading's angle (rad), value (m) and scan index
  std::vector<Bin> bins;        ///< the direction bins kept
  std::vector<int> bin_of;      ///< reading -> bin (-1: not used)
  double width = 0.0;           ///< bin width, radians (0: fixed grid, bins by exact angle)
  bool trend = false;           ///< windows: each bin has a time trend
  double t_mean = 0.0;          ///< mean scan index of the binned readings (the drift's centre)
  double window_min = 0.0;  ///< the sensor's reading window, metres (the outlier floor's support)
  double window_max = 1.0;
  bool intensity = false;  ///< the bins carry an intensity
  double i_ref = kNaN;  ///< the median bin's intensity (the darkness reference; NaN: none recorded)
  /// dequantised data: the reading each y was spread from (its grid cell's centre)
  std::vector<double> y_cell;
};

/// Calls fn(i, bin, fit) for every reading i in a bin that has a location fit, in reading order.
template <class Fn>
void forEachFitted(const BinnedReadings& d, const std::vector<BinFit>& f, Fn fn) {
  for (std::size_t i = 0; i < d.y.size(); ++i) {
    const int bi = d.bin_of[i];
    if (bi < 0 || f[static_cast<std::size_t>(bi)].n == 0) continue;
    fn(i, d.bins[static_cast<std::size_t>(bi)], f[static_cast<std::size_t>(bi)]);
  }
}

/// The bins of `s`: a fixed beam grid binned by angle exactly, otherwise bins as wide as the
/// median beam spacing; with `window` > 0, per window of that many scans (each with a time trend).
/// Bins with too few readings are left out (bin_of -1).
BinnedReadings makeBins(const StaticScans& s, std::size_t window);

/// Mean scan index of the binned readings (the drift's centre).
void setMeanTime(BinnedReadings& d);

/// Each bin's darkness against the median bin's intensity (upper median of the log intensities).
void setDarkness(BinnedReadings& d);

/// Whether the bins' intensities vary (3 bins or more over 10 % from the median): a dark
/// surface can show. Not with one recorded value (some drivers report a constant) or none.
bool darknessVaries(const BinnedReadings& d);

/// Location of every bin from the readings with train[scan] (all when empty), after removing
/// a drift c (t - t_mean): mean, and linear terms in angle (irregular grids) and time (windows).
std::vector<BinFit> fitBins(const BinnedReadings& d, const std::vector<bool>& train, double drift);

/// The readings with each one spread uniformly over its grid cell of width q (dequantise, seeded
/// by `seed`; y_cell keeps the reading each was spread from): where the readings lie on a grid,
/// every model is scored on these, the rounded one through its cell probabilities.
BinnedReadings dequantised(const BinnedReadings& d, double q, std::uint64_t seed);

}  // namespace lidarcal::diagnosis::static_scene
