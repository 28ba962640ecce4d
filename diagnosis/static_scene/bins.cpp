// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/static_scene/bins.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

#include <Eigen/Dense>

#include "common/pose2.hpp"
#include "diagnosis/dequantise.hpp"

namespace lidarcal::diagnosis::static_scene {
namespace {

/// Geometric mean of the readings' intensities (those above zero; NaN when none).
double meanIntensity(const StaticScans& s, const std::vector<std::size_t>& idx) {
  double sum = 0.0, n = 0.0;
  for (std::size_t i : idx) {
    const double v = s.readings[i].intensity;
    if (!(v > 0.0) || !std::isfinite(v)) continue;
    sum += std::log(v);
    n += 1.0;
  }
  return n > 0.0 ? std::exp(sum / n) : kNaN;
}

}  // namespace

void setMeanTime(BinnedReadings& d) {
  double tw = 0.0;
  std::size_t used = 0;
  for (std::size_t i = 0; i < d.t.size(); ++i)
    if (d.bin_of[i] >= 0) {
      tw += d.t[i];
      ++used;
    }
  d.t_mean = used ? tw / static_cast<double>(used) : 0.0;
}

void setDarkness(BinnedReadings& d) {
  std::vector<double> log_i;
  for (const Bin& b : d.bins)
    if (std::isfinite(b.intensity)) log_i.push_back(std::log(b.intensity));
  if (log_i.empty()) return;
  const double med = upperMedian(log_i);
  d.i_ref = std::exp(med);
  for (Bin& b : d.bins)
    if (std::isfinite(b.intensity)) b.dark = med - std::log(b.intensity);
}

bool darknessVaries(const BinnedReadings& d) {
  if (!d.intensity) return false;
  std::size_t away = 0;
  for (const Bin& b : d.bins) away += std::abs(b.dark) > 0.1;
  return away >= 3;
}

BinnedReadings makeBins(const StaticScans& s, std::size_t window) {
  BinnedReadings d;
  const std::size_t n = s.readings.size();
  d.a.resize(n);
  d.y.resize(n);
  d.t.resize(n);
  double ymax = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    d.a[i] = wrapAngle(s.readings[i].angle_rad);
    d.y[i] = s.readings[i].range_m;
    d.t[i] = static_cast<double>(s.readings[i].scan);
    ymax = std::max(ymax, d.y[i]);
  }
  d.window_min = s.range_min_m;
  d.window_max = s.range_max_m < 1e8 ? s.range_max_m : 1.25 * ymax;
  // A fixed beam grid (the same angles every scan) bins by angle exactly; otherwise bins as
  // wide as the median beam spacing, with a linear trend in angle inside each.
  std::set<long long> angles;
  for (std::size_t i = 0; i < n; ++i) angles.insert(std::llround(d.a[i] * 1e7));
  const double beams = s.beams_per_scan > 0 ? static_cast<double>(s.beams_per_scan) : 360.0;
  const bool exact = static_cast<double>(angles.size()) <= 1.5 * beams;
  if (!exact) d.width = 2.0 * kPi / beams;
  d.trend = window > 0;
  // Key: (window, angle).
  std::map<std::pair<long long, long long>, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < n; ++i) {
    const long long w = window > 0 ? static_cast<long long>(s.readings[i].scan / window) : 0;
    const long long a = exact ? std::llround(d.a[i] * 1e7)
                              : static_cast<long long>(std::floor((d.a[i] + kPi) / d.width));
    groups[{w, a}].push_back(i);
  }
  const std::size_t scans_per_bin = window > 0 ? window : s.scans;
  const std::size_t min_n = window > 0 ? std::max<std::size_t>(5, (3 * window) / 4)
                                       : std::max<std::size_t>(8, s.scans / 10);
  d.bin_of.assign(n, -1);
  for (auto& [key, idx] : groups) {
    if (idx.size() < min_n) continue;
    (void)scans_per_bin;
    Bin b;
    b.window = static_cast<int>(key.first);
    double lo = kInf, hi = -kInf, sum = 0.0;
    for (std::size_t i : idx) {
      sum += d.a[i];
      lo = std::min(lo, d.a[i]);
      hi = std::max(hi, d.a[i]);
    }
    b.angle = sum / static_cast<double>(idx.size());
    b.slope = hi - lo > 1e-6;
    b.idx = std::move(idx);
    if (s.has_intensity) b.intensity = meanIntensity(s, b.idx);
    for (std::size_t i : b.idx) d.bin_of[i] = static_cast<int>(d.bins.size());
    d.bins.push_back(std::move(b));
  }
  setMeanTime(d);
  d.intensity = s.has_intensity;
  setDarkness(d);
  return d;
}

std::vector<BinFit> fitBins(const BinnedReadings& d, const std::vector<bool>& train, double drift) {
  std::vector<BinFit> out(d.bins.size());
  std::vector<double> ys;
  for (std::size_t b = 0; b < d.bins.size(); ++b) {
    const Bin& bin = d.bins[b];
    BinFit& f = out[b];
    double sa = 0.0, st = 0.0, n = 0.0;
    ys.clear();
    for (std::size_t i : bin.idx) {
      if (!train.empty() && !train[static_cast<std::size_t>(d.t[i])]) continue;
      sa += d.a[i];
      st += d.t[i];
      n += 1.0;
      ys.push_back(d.y[i] - drift * (d.t[i] - d.t_mean));
    }
    const int p = 1 + (bin.slope ? 1 : 0) + (d.trend ? 1 : 0);
    if (n < static_cast<double>(p) + 2.0) {
      f.n = 0.0;
      continue;
    }
    f.n = n;
    f.abar = sa / n;
    f.tbar = st / n;
    // Least squares in the centred columns [1, a - abar, t - tbar].
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d aty = Eigen::Vector3d::Zero();
    std::size_t k = 0;
    for (std::size_t i : bin.idx) {
      if (!train.empty() && !train[static_cast<std::size_t>(d.t[i])]) continue;
      const Eigen::Vector3d x(1.0, bin.slope ? d.a[i] - f.abar : 0.0,
                              d.trend ? d.t[i] - f.tbar : 0.0);
      ata += x * x.transpose();
      aty += x * ys[k++];
    }
    for (int j = 0; j < 3; ++j)
      if (ata(j, j) <= 0.0) ata(j, j) = 1.0;
    const Eigen::Vector3d c = ata.ldlt().solve(aty);
    f.m = c(0);
    f.g = c(1);
    f.h = c(2);
    f.med = upperMedian(ys);
    double ss = 0.0;
    k = 0;
    for (std::size_t i : bin.idx) {
      if (!train.empty() && !train[static_cast<std::size_t>(d.t[i])]) continue;
      const double r = ys[k++] - f.at(d.a[i], d.t[i]);
      ss += r * r;
    }
    f.s2 = ss / std::max(n - static_cast<double>(p), 1.0);
  }
  return out;
}

BinnedReadings dequantised(const BinnedReadings& d, double q, std::uint64_t seed) {
  BinnedReadings r = d;
  r.y_cell = d.y;
  dequantise(r.y, q, seed);
  return r;
}

}  // namespace lidarcal::diagnosis::static_scene
