// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/span_walls.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <stdexcept>
#include <utility>

#include <Eigen/Dense>

#include "common/pose2.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {
namespace {

std::string degrees(double rad) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f deg", rad2deg(rad));
  return text;
}

std::string metres(double m) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f m", m);
  return text;
}

/// The surfaces of `stop` seen in enough scans to be a span's wall.
std::vector<const WallSurface*> candidates(const std::vector<WallSurface>& surfaces,
                                           std::size_t stop, std::size_t stop_scans,
                                           const SpanConfig& c) {
  std::vector<const WallSurface*> out;
  for (const auto& s : surfaces)
    if (s.stop == stop &&
        static_cast<double>(s.scans) >= c.min_scan_fraction * static_cast<double>(stop_scans))
      out.push_back(&s);
  return out;
}

std::vector<const WallSurface*> near(const std::vector<const WallSurface*>& from,
                                     double bearing_rad, const SpanConfig& c) {
  std::vector<const WallSurface*> out;
  for (const WallSurface* s : from)
    if (std::abs(wrapAngle(s->normal_rad - bearing_rad)) <= c.max_bearing_error_rad)
      out.push_back(s);
  return out;
}

/// The pair of parallel surfaces (one near each bearing) whose distances add up nearest the span,
/// or the reason there is none (status and field of `m`).
std::pair<const WallSurface*, const WallSurface*> choosePair(
    const std::vector<WallSurface>& surfaces, const ReferenceSpan& span, std::size_t stop_scans,
    const SpanConfig& c, SpanMatch& m) {
  const auto all = candidates(surfaces, span.stop, stop_scans, c);
  const std::string seen =
      "; the walls seen at stop " + std::to_string(span.stop) +
      " (normal direction, distance as read): " + surfaceList(surfaces, span.stop);
  const auto a = near(all, span.bearing_a_rad, c), b = near(all, span.bearing_b_rad, c);
  for (const auto& [side, found, bearing] :
       {std::make_tuple("bearing_a_deg", &a, span.bearing_a_rad),
        std::make_tuple("bearing_b_deg", &b, span.bearing_b_rad)})
    if (found->empty()) {
      m.field = side;
      m.status =
          "no wall within " + degrees(c.max_bearing_error_rad) + " of " + degrees(bearing) + seen;
      return {nullptr, nullptr};
    }
  std::pair<const WallSurface*, const WallSurface*> best{nullptr, nullptr};
  double best_error = 1e300, least_skew = 1e300;
  for (const WallSurface* x : a)
    for (const WallSurface* y : b) {
      const double skew = std::abs(wrapAngle(x->normal_rad - y->normal_rad - kPi));
      least_skew = std::min(least_skew, skew);
      if (x == y || skew > c.max_parallel_error_rad) continue;
      const double error = std::abs(x->distance_m + y->distance_m - span.distance_m);
      if (error < best_error) best_error = error, best = {x, y};
    }
  if (!best.first) {
    m.field = "bearing_b_deg";
    m.status = "the walls near the two bearings are not parallel: the nearest pair is " +
               degrees(least_skew) + " from facing each other (at most " +
               degrees(c.max_parallel_error_rad) + ")" + seen;
    return best;
  }
  if (best_error > 0.1 + c.max_distance_error_fraction * span.distance_m) {
    m.field = "distance_m";
    m.status = "the parallel walls near the two bearings read " +
               metres(best.first->distance_m + best.second->distance_m) +
               " apart at the nearest, too far from distance_m" + seen;
    return {nullptr, nullptr};
  }
  return best;
}

/// Drops the beams whose mean lies off the straight line through the others (a return near a
/// corner, a mixed pixel at an edge): more than 4 robust standard deviations (1.4826 times the
/// median absolute deviation, at least 1 mm) from their total-least-squares line; twice.
void dropOffLine(std::vector<SpanWall::Beam>& beams) {
  for (int round = 0; round < 2 && beams.size() >= 3; ++round) {
    std::vector<Eigen::Vector2d> pts;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (const auto& b : beams)
      pts.emplace_back(b.reading_m * std::cos(b.angle_rad), b.reading_m * std::sin(b.angle_rad));
    for (const auto& p : pts) centre += p / static_cast<double>(pts.size());
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (const auto& p : pts) scatter += (p - centre) * (p - centre).transpose();
    const Eigen::Vector2d normal =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(scatter).eigenvectors().col(0);
    std::vector<double> off, spread;
    for (const auto& p : pts) off.push_back((p - centre).dot(normal));
    const double middle = median(off);
    for (double o : off) spread.push_back(std::abs(o - middle));
    const double limit = std::max(4.0 * 1.4826 * median(spread), 1e-3);
    std::vector<SpanWall::Beam> kept;
    for (std::size_t k = 0; k < beams.size(); ++k)
      if (std::abs(off[k] - middle) <= limit) kept.push_back(beams[k]);
    if (kept.size() == beams.size()) return;
    beams = std::move(kept);
  }
}

/// The beams of surface `s`: readings averaged per beam over the scans, near the normal, read
/// in at least half of the scans that saw the surface, on its line (dropOffLine).
SpanWall gatherBeams(const LandmarkObservations& obs, const WallSurface& s, const SpanConfig& c) {
  SpanWall w;
  w.stop = s.stop;
  w.wall = s.wall;
  w.normal_rad = s.normal_rad;
  w.distance_m = s.distance_m;
  std::map<long long, SpanWall::Beam> beams;  // by beam index, else by angle to 1e-5 rad
  for (const WallSighting& ws : obs.walls) {
    if (ws.stop != s.stop || ws.wall != s.wall) continue;
    for (const BeamReading& b : ws.beams) {
      if (!std::isfinite(b.range_m) ||
          std::abs(wrapAngle(b.angle_rad - s.normal_rad)) > c.max_incidence_rad)
        continue;
      SpanWall::Beam& e = beams[beamKey(b)];
      e.angle_rad += b.angle_rad;
      e.reading_m += b.range_m;
      e.beam = b.beam;
      ++e.count;
    }
  }
  for (auto& [key, b] : beams) {
    if (2 * b.count < s.scans) continue;
    b.angle_rad /= static_cast<double>(b.count);
    b.reading_m /= static_cast<double>(b.count);
    w.beams.push_back(b);
  }
  dropOffLine(w.beams);
  return w;
}

/// The mean over the scans of the two walls' summed distances, and its standard error.
void measureSpan(const LandmarkObservations& obs, const WallSurface& a, const WallSurface& b,
                 SpanMatch& m) {
  std::map<std::size_t, std::pair<double, int>> by_scan;  // scan -> summed distance, walls seen
  for (const WallSighting& ws : obs.walls)
    if (ws.stop == a.stop && (ws.wall == a.wall || ws.wall == b.wall)) {
      auto& e = by_scan[ws.scan];
      e.first += ws.distance_m;
      ++e.second;
    }
  double sum = 0.0, sum2 = 0.0;
  for (const auto& [scan, e] : by_scan)
    if (e.second == 2) sum += e.first, sum2 += e.first * e.first, ++m.scans;
  const double n = static_cast<double>(m.scans);
  m.measured_m = m.scans ? sum / n : kNaN;
  m.measured_se_m =
      m.scans > 1 ? std::sqrt(std::max(0.0, (sum2 - sum * sum / n) / (n - 1.0)) / n) : kNaN;
}

}  // namespace

long long beamKey(const BeamReading& b) {
  return b.beam != kUnknownBeam ? static_cast<long long>(b.beam)
                                : -1 - std::llround(b.angle_rad * 1e5);
}

void SpanConfig::validate() const {
  if (!(max_bearing_error_rad > 0.0 && max_bearing_error_rad < 1.6))
    throw std::invalid_argument("SpanConfig: max_bearing_error_rad must be in (0, 1.6)");
  if (!(max_parallel_error_rad > 0.0 && max_parallel_error_rad < 0.8))
    throw std::invalid_argument("SpanConfig: max_parallel_error_rad must be in (0, 0.8)");
  if (!(max_distance_error_fraction > 0.0))
    throw std::invalid_argument("SpanConfig: max_distance_error_fraction must be positive");
  if (!(min_scan_fraction >= 0.0 && min_scan_fraction <= 1.0))
    throw std::invalid_argument("SpanConfig: min_scan_fraction must be in [0, 1]");
  if (!(max_incidence_rad > 0.0 && max_incidence_rad < 1.5))
    throw std::invalid_argument("SpanConfig: max_incidence_rad must be in (0, 1.5)");
}

std::vector<WallSurface> wallSurfaces(const std::vector<WallSighting>& walls) {
  struct Sums {
    double sin = 0.0, cos = 0.0, distance = 0.0;
    std::set<std::size_t> scans;
    std::size_t n = 0;
  };
  std::map<std::pair<std::size_t, int>, Sums> by_surface;
  for (const WallSighting& w : walls) {
    if (w.wall <= 0) continue;
    Sums& s = by_surface[{w.stop, w.wall}];
    s.sin += std::sin(w.normal_rad);
    s.cos += std::cos(w.normal_rad);
    s.distance += w.distance_m;
    s.scans.insert(w.scan);
    ++s.n;
  }
  std::vector<WallSurface> out;
  for (const auto& [key, s] : by_surface)
    out.push_back({key.first, key.second, std::atan2(s.sin, s.cos),
                   s.distance / static_cast<double>(s.n), s.scans.size()});
  return out;
}

std::string surfaceList(const std::vector<WallSurface>& surfaces, std::size_t stop,
                        std::size_t limit) {
  std::vector<const WallSurface*> at;
  for (const auto& s : surfaces)
    if (s.stop == stop) at.push_back(&s);
  if (at.empty()) return "none";
  std::stable_sort(at.begin(), at.end(),
                   [](const WallSurface* a, const WallSurface* b) { return a->scans > b->scans; });
  if (at.size() > limit) at.resize(limit);
  std::stable_sort(at.begin(), at.end(), [](const WallSurface* a, const WallSurface* b) {
    return a->normal_rad < b->normal_rad;
  });
  std::string text;
  for (const WallSurface* s : at) {
    char item[64];
    std::snprintf(item, sizeof item, "%s%.0f deg at %.2f m", text.empty() ? "" : ", ",
                  rad2deg(s->normal_rad), s->distance_m);
    text += item;
  }
  return text;
}

SpanReadings spanReadings(const LandmarkObservations& obs, const Reference& ref,
                          const SpanConfig& config) {
  config.validate();
  const std::vector<WallSurface> surfaces = wallSurfaces(obs.walls);
  std::map<std::size_t, std::set<std::size_t>> stop_scans;
  for (const WallSighting& w : obs.walls) stop_scans[w.stop].insert(w.scan);
  SpanReadings out;
  // (stop, id) -> index into out.walls
  std::map<std::pair<std::size_t, int>, std::size_t> wall_index;
  for (std::size_t k = 0; k < ref.spans.size(); ++k) {
    const ReferenceSpan& span = ref.spans[k];
    SpanMatch m;
    m.entry = k;
    m.stop = span.stop;
    m.reference_m = span.distance_m;
    const auto [a, b] = choosePair(surfaces, span, stop_scans[span.stop].size(), config, m);
    if (a && b) {
      measureSpan(obs, *a, *b, m);
      for (const auto& [s, side, index] : {std::make_tuple(a, "bearing_a_deg", &m.wall_a),
                                           std::make_tuple(b, "bearing_b_deg", &m.wall_b)}) {
        auto it = wall_index.find({s->stop, s->wall});
        if (it == wall_index.end()) {
          it = wall_index.emplace(std::make_pair(s->stop, s->wall), out.walls.size()).first;
          out.walls.push_back(gatherBeams(obs, *s, config));
        }
        *index = it->second;
        if (out.walls[it->second].beams.size() < 3 && m.ok()) {
          m.field = side;
          m.status = "the wall at " + degrees(s->normal_rad) +
                     " has too few beams read in half of its scans within " +
                     degrees(config.max_incidence_rad) + " of its normal (" +
                     std::to_string(out.walls[it->second].beams.size()) + "; at least 3 needed)";
        }
      }
    }
    out.matches.push_back(std::move(m));
  }
  return out;
}

}  // namespace lidarcal::calibration
