// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/static_scene/walls.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/Core>

#include "common/pose2.hpp"
#include "detectors/walls.hpp"

namespace lidarcal::diagnosis::static_scene {
namespace {

/// The bin mean's point in the sensor frame.
Eigen::Vector2d binPoint(const BinnedReadings& d, const std::vector<BinFit>& f, std::size_t b) {
  return Eigen::Vector2d(f[b].m * std::cos(d.bins[b].angle), f[b].m * std::sin(d.bins[b].angle));
}

/// Bins by window, then by angle.
std::vector<std::size_t> binOrder(const BinnedReadings& d) {
  std::vector<std::size_t> order(d.bins.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return d.bins[a].window != d.bins[b].window ? d.bins[a].window < d.bins[b].window
                                                : d.bins[a].angle < d.bins[b].angle;
  });
  return order;
}

/// Angular step between neighbouring bins: the bin width, else the median gap.
double binStep(const BinnedReadings& d, const std::vector<std::size_t>& order) {
  if (d.width > 0.0) return d.width;
  std::vector<double> gaps;
  for (std::size_t k = 1; k < order.size(); ++k)
    gaps.push_back(d.bins[order[k]].angle - d.bins[order[k - 1]].angle);
  return gaps.empty() ? deg2rad(1.0) : upperMedian(gaps);
}

/// Runs: neighbours in angle whose points are close (no depth jump, no missing beam between).
/// Marks the bins on both sides of a depth discontinuity as edges.
std::vector<std::vector<std::size_t>> findRuns(BinnedReadings& d, const std::vector<BinFit>& f,
                                               const std::vector<std::size_t>& order, double step) {
  std::vector<std::vector<std::size_t>> runs;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t b = order[k];
    if (f[b].n == 0) continue;
    bool joins = false;
    if (!runs.empty() && d.bins[runs.back().back()].window == d.bins[b].window) {
      const std::size_t prev = runs.back().back();
      const double da = d.bins[b].angle - d.bins[prev].angle;
      const double gap = (binPoint(d, f, b) - binPoint(d, f, prev)).norm();
      joins = da <= 2.5 * step && gap <= std::max(0.15, 4.0 * f[b].m * da);
      if (!joins && da <= 2.5 * step && std::abs(f[b].m - f[prev].m) > 0.05) {
        // A depth discontinuity between neighbouring beams: both sides may see mixed pixels.
        for (std::size_t e : {b, prev}) {
          d.bins[e].edge = true;
          d.bins[e].near = std::min(f[b].m, f[prev].m);
          d.bins[e].far = std::max(f[b].m, f[prev].m);
        }
      }
    }
    if (joins)
      runs.back().push_back(b);
    else
      runs.push_back({b});
  }
  return runs;
}

/// Incidence from the local slope of the means (any surface): tan(phi) = |dm / da| / m.
void setIncidences(BinnedReadings& d, const std::vector<BinFit>& f,
                   const std::vector<std::vector<std::size_t>>& runs) {
  for (const auto& run : runs) {
    for (std::size_t k = 0; k < run.size(); ++k) {
      if (run.size() < 3) break;
      const std::size_t lo = run[k == 0 ? 0 : k - 1], hi = run[k + 1 == run.size() ? k : k + 1];
      const double da = d.bins[hi].angle - d.bins[lo].angle;
      if (!(da > 0.0)) continue;
      const double slope = (f[hi].m - f[lo].m) / da;
      Bin& b = d.bins[run[k]];
      b.cos_inc = 1.0 / std::sqrt(1.0 + std::pow(slope / f[run[k]].m, 2));
      b.inc_known = true;
    }
  }
}

}  // namespace

std::vector<Line> findWallLines(BinnedReadings& d, const std::vector<BinFit>& f) {
  const std::vector<std::size_t> order = binOrder(d);
  const auto runs = findRuns(d, f, order, binStep(d, order));
  setIncidences(d, f, runs);
  // Straight pieces of each run: within 2.5 cm of their line, 8 bins at least, the run's two end
  // bins (beside a jump or a gap) left out.
  const detectors::RunWallConfig straight;
  std::vector<Line> lines;
  for (const auto& run : runs) {
    std::vector<Eigen::Vector2d> pts;
    pts.reserve(run.size());
    for (std::size_t b : run) pts.push_back(binPoint(d, f, b));
    for (const detectors::Wall& piece : detectors::findWallsInRun(pts, straight)) {
      const Line l{piece.normal_rad, piece.distance_m};
      const int w = static_cast<int>(lines.size());
      lines.push_back(l);
      for (const auto k : piece.inliers) {
        Bin& bin = d.bins[run[static_cast<std::size_t>(k)]];
        bin.wall = w;
        bin.cos_inc = std::abs(std::cos(bin.angle - l.theta));
        bin.inc_known = true;
      }
    }
  }
  return lines;
}

}  // namespace lidarcal::diagnosis::static_scene
