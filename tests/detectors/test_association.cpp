// SPDX-License-Identifier: BSD-3-Clause
// Association across stops on synthetic detections whose truth the test knows: drift, occlusion,
// spurious circles, close landmarks, and the order of the input.

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "detectors/association.hpp"

namespace lidarcal::detectors {
namespace {

struct Synthetic {
  std::vector<ScanDetections> scans;
  std::vector<Pose2> viewpoints;
  std::vector<std::vector<int>> truth;  // per scan, per detection: landmark index + 1, 0 spurious
};

struct Field {
  std::vector<std::pair<double, double>> landmarks{
      {1.5, 0.75}, {0.3, 2.2}, {2.4, 3.4}, {3.9, -1.3}, {0.9, -2.8}};
  int stops = 10, scans_per_stop = 5;
  // odometry drift accumulating along the path (x; half of it in y)
  double drift_per_stop_m = 0.03;
  double drift_yaw_per_stop_rad = 0.005;  // heading drift accumulating along the path
  double noise_m = 0.02;                  // scatter of the detected centre
  // range stretched by 1 + bias * range (a lidar's range bias: +12% at 4 m)
  double bias_per_m = 0.03;
  double occlusion = 0.2;          // probability that a landmark is hidden at a stop
  double spurious_per_scan = 0.3;  // random circles anywhere (expected number per scan)
};

Synthetic make(const Field& s, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0), pos(-1.0, 5.0);
  Synthetic out;
  for (int k = 0; k < s.stops; ++k) {
    const Pose2 commanded{0.3 * k, 0.0, 0.0};
    const Pose2 actual{commanded.x_m + s.drift_per_stop_m * k,
                       commanded.y_m - 0.5 * s.drift_per_stop_m * k, s.drift_yaw_per_stop_rad * k};
    std::vector<bool> hidden(s.landmarks.size());
    // Where each landmark appears in the world at this stop (commanded pose, biased range).
    std::vector<std::pair<double, double>> apparent;
    for (const auto& l : s.landmarks) {
      double x = 0, y = 0, wx = 0, wy = 0;
      actual.toSensor(l.first, l.second, x, y);
      const double k_bias = 1.0 + s.bias_per_m * std::hypot(x, y);
      commanded.toWorld(k_bias * x, k_bias * y, wx, wy);
      apparent.emplace_back(wx, wy);
    }
    for (auto&& h : hidden) h = u(rng) < s.occlusion;
    for (int i = 0; i < s.scans_per_stop; ++i) {
      ScanDetections sd;
      sd.scan_index = static_cast<std::size_t>(k * s.scans_per_stop + i);
      sd.stop = static_cast<std::size_t>(k);
      std::vector<int> t;
      for (std::size_t l = 0; l < s.landmarks.size(); ++l) {
        if (hidden[l]) continue;
        double x = 0, y = 0;
        actual.toSensor(s.landmarks[l].first, s.landmarks[l].second, x, y);
        const double r = std::hypot(x, y) * (1.0 + s.bias_per_m * std::hypot(x, y)),
                     b = std::atan2(y, x);
        Detection d;
        d.centre_x_m = r * std::cos(b) + s.noise_m * n(rng);
        d.centre_y_m = r * std::sin(b) + s.noise_m * n(rng);
        d.bearing_rad = std::atan2(d.centre_y_m, d.centre_x_m);
        d.range_m = std::hypot(d.centre_x_m, d.centre_y_m);
        d.radius_m = 0.12;
        sd.detections.push_back(d);
        t.push_back(static_cast<int>(l) + 1);
      }
      for (int q = std::poisson_distribution<int>(s.spurious_per_scan)(rng); q > 0; --q) {
        // Anywhere but within 0.5 m of where a landmark appears: a circle there, at a stop where
        // the landmark is hidden, cannot be told from a weak detection of the landmark itself.
        double wx = 0, wy = 0;
        do {
          wx = pos(rng), wy = pos(rng);
        } while (std::any_of(apparent.begin(), apparent.end(), [&](const auto& l) {
          return std::hypot(l.first - wx, l.second - wy) < 0.5;
        }));
        Detection d;
        commanded.toSensor(wx, wy, d.centre_x_m, d.centre_y_m);
        d.bearing_rad = std::atan2(d.centre_y_m, d.centre_x_m);
        d.range_m = std::hypot(d.centre_x_m, d.centre_y_m);
        d.radius_m = 0.02;
        sd.detections.push_back(d);
        t.push_back(0);
      }
      out.scans.push_back(sd);
      out.viewpoints.push_back(commanded);
      out.truth.push_back(t);
    }
  }
  return out;
}

/// Checks one id per landmark, distinct ids, spurious detections unlabelled.
void expectCorrect(const Synthetic& s, const Association& a, std::size_t landmarks) {
  ASSERT_EQ(a.landmarks.size(), landmarks);
  std::map<int, int> id_of_truth, truth_of_id;
  for (std::size_t i = 0; i < s.scans.size(); ++i)
    for (std::size_t j = 0; j < s.scans[i].detections.size(); ++j) {
      const int t = s.truth[i][j], id = a.ids[i][j];
      if (t == 0) {
        EXPECT_EQ(id, 0) << "spurious detection labelled";
        continue;
      }
      ASSERT_GT(id, 0) << "landmark " << t << " unlabelled in scan " << i;
      if (!id_of_truth.count(t)) id_of_truth[t] = id;
      if (!truth_of_id.count(id)) truth_of_id[id] = t;
      EXPECT_EQ(id_of_truth[t], id) << "landmark " << t << " got two ids";
      EXPECT_EQ(truth_of_id[id], t) << "id " << id << " given to two landmarks";
    }
}

TEST(Associate, DriftOcclusionAndSpuriousCirclesOverManySeeds) {
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    SCOPED_TRACE(seed);
    const Synthetic s = make(Field{}, seed);
    const Association a = associate(s.scans, s.viewpoints, AssociationConfig{});
    expectCorrect(s, a, 5);
    for (const auto& l : a.landmarks) EXPECT_GE(l.stops, 3u);
  }
}

TEST(Associate, IdsDoNotDependOnTheOrderOfTheInput) {
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    SCOPED_TRACE(seed);
    const Synthetic s = make(Field{}, seed);
    const Association a = associate(s.scans, s.viewpoints, AssociationConfig{});
    std::vector<std::size_t> order(s.scans.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::shuffle(order.begin(), order.end(), std::mt19937_64(seed + 1000));
    Synthetic p;
    for (auto i : order) p.scans.push_back(s.scans[i]), p.viewpoints.push_back(s.viewpoints[i]);
    // Also reverse the detections inside every scan.
    for (std::size_t i = 0; i < p.scans.size(); ++i) {
      auto& d = p.scans[i].detections;
      std::reverse(d.begin(), d.end());
    }
    const Association b = associate(p.scans, p.viewpoints, AssociationConfig{});
    ASSERT_EQ(a.landmarks.size(), b.landmarks.size());
    for (std::size_t k = 0; k < order.size(); ++k) {
      const std::size_t n = s.scans[order[k]].detections.size();
      for (std::size_t j = 0; j < n; ++j) EXPECT_EQ(b.ids[k][n - 1 - j], a.ids[order[k]][j]);
    }
    for (std::size_t l = 0; l < a.landmarks.size(); ++l) {
      EXPECT_DOUBLE_EQ(a.landmarks[l].x_m, b.landmarks[l].x_m);
      EXPECT_EQ(a.landmarks[l].detections, b.landmarks[l].detections);
    }
  }
}

TEST(Associate, IdsFollowFirstSightingThenBearing) {
  Field setup;
  setup.occlusion = 0.0;
  const Synthetic s = make(setup, 3);
  const Association a = associate(s.scans, s.viewpoints, AssociationConfig{});
  ASSERT_EQ(a.landmarks.size(), 5u);
  // All five are seen in scan 0: ids go counter-clockwise from the sensor's x axis there.
  std::vector<double> bearings;
  for (const auto& l : a.landmarks) {
    EXPECT_EQ(l.first_scan, 0u);
    double x = 0, y = 0;
    s.viewpoints[0].toSensor(l.x_m, l.y_m, x, y);
    const double b = std::atan2(y, x);
    bearings.push_back(b < 0 ? b + 2 * kPi : b);
  }
  EXPECT_TRUE(std::is_sorted(bearings.begin(), bearings.end()));
}

TEST(Associate, LandmarksSeenAtTooFewStopsAreDiscarded) {
  Field s;
  s.stops = 2;
  s.occlusion = 0.0;
  s.spurious_per_scan = 0;
  const Synthetic two = make(s, 1);
  AssociationConfig cfg;
  cfg.min_stops = 3;  // capped at the 2 stops of the input: everything is kept
  EXPECT_EQ(associate(two.scans, two.viewpoints, cfg).landmarks.size(), 5u);
  // With 10 stops, a landmark present at 2 stops only is discarded.
  s.stops = 10;
  Synthetic ten = make(s, 1);
  for (std::size_t i = 0; i < ten.scans.size(); ++i) {
    if (ten.scans[i].stop < 2) continue;
    auto& d = ten.scans[i].detections;
    for (std::size_t j = d.size(); j-- > 0;)
      if (ten.truth[i][j] == 3)
        d.erase(d.begin() + static_cast<std::ptrdiff_t>(j)),
            ten.truth[i].erase(ten.truth[i].begin() + static_cast<std::ptrdiff_t>(j));
  }
  const Association a = associate(ten.scans, ten.viewpoints, cfg);
  EXPECT_EQ(a.landmarks.size(), 4u);
  EXPECT_EQ(a.discarded_components, 1u);
  EXPECT_EQ(a.discarded_few_stops, 2u * 5u);
}

TEST(Associate, LandmarksCloserThanTheLinkDistanceAreSplit) {
  Field s;
  // 0.28 m apart: linked, but seen together in every scan
  s.landmarks = {{1.5, 1.0}, {1.5, 1.28}, {3.0, -1.0}};
  s.noise_m = 0.01;
  s.bias_per_m = 0.0;
  s.drift_per_stop_m = 0.0;
  s.occlusion = 0.0;
  s.spurious_per_scan = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    SCOPED_TRACE(seed);
    const Synthetic syn = make(s, seed);
    const Association a = associate(syn.scans, syn.viewpoints, AssociationConfig{});
    expectCorrect(syn, a, 3);
  }
}

/// One strong stop cluster of one detection at (x, y), at `stop`.
StopCluster cluster(std::size_t stop, double x, double y) {
  StopCluster c;
  c.stop = stop;
  c.strong = true;
  c.x_m = x, c.y_m = y;
  c.detections = 1;
  c.radius_m = 0.1;
  c.first = DetectionKey{stop, stop, 0.0, x, y};
  return c;
}

// One object first found as two tracks (its second sighting too far from the first), then seen
// between them: the tracks merge, and every sighting gets the landmark's id (single linkage
// would join all three too). Without the merge neither track reaches min_stops = 3.
TEST(StopLinker, AnObjectFoundAsTwoTracksMergesWhenASightingBridgesThem) {
  StopLinker linker(AssociationConfig{}, 3);
  const auto a = linker.add({cluster(0, 0.0, 0.0)}, 0);
  const auto b = linker.add({cluster(1, 0.5, 0.0)}, 0);
  EXPECT_NE(a[0], b[0]);
  const auto c = linker.add({cluster(2, 0.25, 0.0)}, 0);
  ASSERT_EQ(linker.merged().size(), 1u);
  TrackIds ids;
  const Association r = linker.finish(ids);
  ASSERT_EQ(r.landmarks.size(), 1u);
  EXPECT_EQ(r.landmarks[0].stops, 3u);
  EXPECT_NEAR(r.landmarks[0].x_m, 0.25, 1e-12);
  for (auto t : {a[0], b[0], c[0]}) EXPECT_EQ(ids.of(t), 1);
}

// Two poles 0.28 m apart (closer than the link distance) seen together at five stops, then one
// of them alone at a position within reach of both: still two landmarks, never merged.
TEST(StopLinker, TracksSeenTogetherNeverMerge) {
  StopLinker linker(AssociationConfig{}, 6);
  for (std::size_t k = 0; k < 5; ++k) linker.add({cluster(k, 1.0, 0.0), cluster(k, 1.0, 0.28)}, 0);
  linker.add({cluster(5, 1.0, 0.14)}, 0);
  EXPECT_TRUE(linker.merged().empty());
  TrackIds ids;
  EXPECT_EQ(linker.finish(ids).landmarks.size(), 2u);
}

// Memory: over a long path past five poles with a new object seen at each stop (a chair leg
// here, a bin there: seen strongly once, never again), the tracks held stay the poles plus the
// objects of the last forget_after_stops stops, however long the path; the poles are found.
TEST(StopLinker, TracksHeldStayBoundedOverALongSequence) {
  AssociationConfig cfg;
  cfg.forget_after_stops = 20;
  const std::size_t stops = 3000;
  StopLinker linker(cfg, stops);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  const std::vector<std::pair<double, double>> poles{
      {1.5, 0.75}, {0.3, 2.2}, {2.4, 3.4}, {3.9, -1.3}, {0.9, -2.8}};
  std::size_t most = 0;
  for (std::size_t k = 0; k < stops; ++k) {
    StopClusters cs;
    for (const auto& p : poles)
      cs.push_back(cluster(k, p.first + noise(rng), p.second + noise(rng)));
    // a new object, never seen again
    cs.push_back(cluster(k, 100.0 + static_cast<double>(k), 50.0));
    std::sort(cs.begin(), cs.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    linker.add(cs, 0);
    most = std::max(most, linker.alive());
  }
  EXPECT_LE(most, poles.size() + cfg.forget_after_stops + 2);
  EXPECT_EQ(linker.tracks(), poles.size() + stops);  // every object got a track at some point
  TrackIds ids;
  const Association r = linker.finish(ids);
  ASSERT_EQ(r.landmarks.size(), poles.size());
  for (const auto& l : r.landmarks) EXPECT_EQ(l.stops, stops);
  EXPECT_EQ(r.discarded_components, stops);
}

// forget_after_stops at its largest value never forgets (no overflow): a track seen at two
// stops far apart still reaches min_stops.
TEST(StopLinker, TheLargestForgettingWindowNeverForgets) {
  AssociationConfig cfg;
  cfg.forget_after_stops = std::numeric_limits<std::size_t>::max();
  StopLinker linker(cfg, 3);
  linker.add({cluster(0, 1.0, 0.0)}, 0);
  linker.add({cluster(1000, 1.0, 0.0)}, 0);
  EXPECT_TRUE(linker.forgotten().empty());
  linker.add({cluster(2000, 1.0, 0.0)}, 0);
  TrackIds ids;
  EXPECT_EQ(linker.finish(ids).landmarks.size(), 1u);
}

TEST(StopLinker, StopsMustComeInIncreasingOrder) {
  StopLinker linker(AssociationConfig{}, 3);
  linker.add({cluster(2, 0.0, 0.0)}, 0);
  EXPECT_THROW(linker.add({cluster(1, 0.0, 0.0)}, 0), std::invalid_argument);
  EXPECT_THROW(linker.add({cluster(3, 0.0, 0.0), cluster(4, 1.0, 0.0)}, 0), std::invalid_argument);
}

TEST(EvenSample, KeepsEveryItemUpToItsCapacityThenAnEvenSpread) {
  EvenSample<int> s(8);
  for (int i = 0; i < 7; ++i) s.offer(i);
  EXPECT_EQ(s.items(), (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));
  for (int i = 7; i < 100; ++i) s.offer(i);
  EXPECT_LT(s.items().size(), 8u);
  EXPECT_EQ(s.offered(), 100u);
  // Evenly spaced from the first item: one stride apart, the last within a stride of the end.
  const auto& v = s.items();
  ASSERT_GE(v.size(), 2u);
  const int stride = v[1] - v[0];
  EXPECT_EQ(v[0], 0);
  for (std::size_t i = 1; i < v.size(); ++i) EXPECT_EQ(v[i] - v[i - 1], stride);
  EXPECT_GT(v.back() + stride, 99 - stride);
}

TEST(Associate, EmptyInputAndBadConfiguration) {
  const Association a = associate({}, {}, AssociationConfig{});
  EXPECT_TRUE(a.landmarks.empty());
  EXPECT_EQ(a.detections, 0u);
  const Synthetic s = make(Field{}, 1);
  std::vector<Pose2> fewer(s.viewpoints.begin(), s.viewpoints.end() - 1);
  EXPECT_THROW(associate(s.scans, fewer, AssociationConfig{}), std::invalid_argument);
  AssociationConfig bad;
  bad.min_link_distance_m = 1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace lidarcal::detectors
