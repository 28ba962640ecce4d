// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/static_scene/scene_changes.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace lidarcal::diagnosis::static_scene {
namespace {

/// A reading this far from its beam's median, and six robust deviations, lies on another surface.
constexpr double kSceneStepM = 0.05;

/// A normal sample's standard deviation over its median absolute deviation.
constexpr double kMadToSigma = 1.4826;

/// Whether bin b saw the scene change: its readings off its median (by kSceneStepM and six
/// robust deviations) come in runs in time, as when an object is moved into or out of the beam
/// or a person walks through it, not scattered over the recording as a sensor's own outliers
/// and mixed pixels are. Wald-Wolfowitz runs test on the off/on labels in scan order (z < -4),
/// with at least 5 off readings and 5 % of the bin's.
bool sceneChanged(const BinnedReadings& d, const Bin& b) {
  std::vector<double> ys;
  for (std::size_t i : b.idx) ys.push_back(d.y[i]);
  const double med = upperMedian(ys);
  std::vector<double> dev;
  for (double y : ys) dev.push_back(std::abs(y - med));
  const double step = std::max(kSceneStepM, 6.0 * kMadToSigma * upperMedian(dev));
  std::vector<std::pair<double, bool>> seq;  // (scan, off)
  for (std::size_t i : b.idx) seq.emplace_back(d.t[i], std::abs(d.y[i] - med) > step);
  std::stable_sort(seq.begin(), seq.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  const auto n = static_cast<double>(seq.size());
  double off = 0.0, runs = seq.empty() ? 0.0 : 1.0;
  for (std::size_t k = 0; k < seq.size(); ++k) {
    off += seq[k].second ? 1.0 : 0.0;
    if (k > 0 && seq[k].second != seq[k - 1].second) runs += 1.0;
  }
  const double on = n - off;
  if (off < 5.0 || off < 0.05 * n || on < 5.0) return false;
  const double mean = 1.0 + 2.0 * off * on / n;
  const double var = 2.0 * off * on * (2.0 * off * on - n) / (n * n * (n - 1.0));
  return var > 0.0 && (runs - mean) / std::sqrt(var) < -4.0;
}

/// Standard error of a normal sample's median over that of its mean: sqrt(pi / 2).
constexpr double kMedianEfficiency = 1.2533141373155003;

}  // namespace

std::size_t dropChangedBins(BinnedReadings& d) {
  std::vector<bool> drop(d.bins.size());
  std::size_t changed = 0;
  for (std::size_t b = 0; b < d.bins.size(); ++b)
    changed += (drop[b] = sceneChanged(d, d.bins[b])) ? 1 : 0;
  if (changed == 0 || static_cast<double>(changed) > 0.5 * static_cast<double>(d.bins.size()))
    return 0;
  std::vector<Bin> kept;
  d.bin_of.assign(d.y.size(), -1);
  for (std::size_t b = 0; b < d.bins.size(); ++b) {
    if (drop[b]) continue;
    for (std::size_t i : d.bins[b].idx) d.bin_of[i] = static_cast<int>(kept.size());
    kept.push_back(std::move(d.bins[b]));
  }
  d.bins = std::move(kept);
  setMeanTime(d);
  setDarkness(d);  // against the median of the bins kept
  return changed;
}

double movedFraction(const BinnedReadings& d) {
  double tmax = 0.0;
  for (double t : d.t) tmax = std::max(tmax, t);
  std::vector<bool> first(static_cast<std::size_t>(tmax) + 1), second(first.size());
  for (std::size_t t = 0; t < first.size(); ++t) {
    first[t] = static_cast<double>(t) <= tmax / 2.0;
    second[t] = !first[t];
  }
  const auto a = fitBins(d, first, 0.0), b = fitBins(d, second, 0.0);
  std::vector<double> diff, se;
  for (std::size_t k = 0; k < d.bins.size(); ++k) {
    if (a[k].n == 0 || b[k].n == 0) continue;
    // Medians: a person walking past, or a beam flickering onto a vehicle's own body, moves a
    // bin's mean by decimetres while the sensor stands still (docs/FINDINGS.md).
    diff.push_back(b[k].med - a[k].med);
    se.push_back(kMedianEfficiency * std::sqrt(a[k].s2 / a[k].n + b[k].s2 / b[k].n));
  }
  if (diff.empty()) return 1.0;
  const double common = upperMedian(diff);
  std::size_t moved = 0;
  std::vector<double> dev;
  for (std::size_t k = 0; k < diff.size(); ++k) {
    moved += std::abs(diff[k] - common) > std::max(5.0 * se[k], 0.01);
    dev.push_back(std::abs(diff[k] - common));
  }
  // Half the beams' means moved by more than 1 cm: the sensor moved, whatever the noise.
  if (upperMedian(dev) > 0.01) return 1.0;
  return static_cast<double>(moved) / static_cast<double>(diff.size());
}

}  // namespace lidarcal::diagnosis::static_scene
