// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include "watch/sighting_window.hpp"

namespace lidarcal::watch {
namespace {

WatchedScan scanWith(std::size_t index, std::vector<PoleId> poles) {
  WatchedScan s;
  s.index = index;
  s.pose.x_m = 0.1 * static_cast<double>(index);
  for (PoleId p : poles) {
    PoleSighting ps;
    ps.pole = p;
    ps.beams.push_back(BeamReading{0.0, 1.0, 0});
    s.poles.push_back(ps);
  }
  return s;
}

TEST(SightingWindow, HoldsAtMostItsCapacityAndCountsItsSightings) {
  SightingWindow w(4);
  for (std::size_t i = 0; i < 10; ++i) w.push(scanWith(i, {1, 2}));
  EXPECT_EQ(w.size(), 4u);
  EXPECT_EQ(w.sightings(), 8u);
  EXPECT_EQ(w.oldest().index, 6u);
  EXPECT_EQ(w.find(5), nullptr);
  ASSERT_NE(w.find(7), nullptr);
  EXPECT_THROW(w.push(scanWith(9, {})), std::invalid_argument);
}

TEST(SightingWindow, ObservationsNumberThePolesSeenOftenEnoughByFirstSighting) {
  SightingWindow w(100);
  // Pole 7 in every scan, pole 3 from scan 2 on, pole 9 once.
  for (std::size_t i = 0; i < 6; ++i) {
    std::vector<PoleId> poles = {7};
    if (i >= 2) poles.insert(poles.begin(), 3);
    if (i == 4) poles.push_back(9);
    w.push(scanWith(i, poles));
  }
  const LandmarkObservations obs = w.observations(1, 5, SpanRules{3, 0.05});
  EXPECT_EQ(obs.commanded.size(), 5u);
  EXPECT_EQ(w.polesIn(1, 5, SpanRules{3, {}}), 2u);
  ASSERT_TRUE(obs.landmark_radius_m);
  EXPECT_EQ(*obs.landmark_radius_m, 0.05);
  // 5 sightings of pole 7 (id 1: seen first) and 4 of pole 3 (id 2); pole 9 left out.
  int ones = 0, twos = 0;
  for (const auto& s : obs.sightings) {
    ones += s.landmark == 1;
    twos += s.landmark == 2;
    EXPECT_EQ(s.stop, s.scan);
    EXPECT_LT(s.stop, 5u);
  }
  EXPECT_EQ(ones, 5);
  EXPECT_EQ(twos, 4);
  // Within a scan by landmark number.
  for (std::size_t k = 1; k < obs.sightings.size(); ++k) {
    if (obs.sightings[k].scan == obs.sightings[k - 1].scan) {
      EXPECT_LT(obs.sightings[k - 1].landmark, obs.sightings[k].landmark);
    }
  }
}

TEST(SightingWindow, RenamesMergedTracks) {
  SightingWindow w(10);
  w.push(scanWith(0, {4}));
  w.push(scanWith(1, {5}));
  w.rename({{5, 4}});
  EXPECT_EQ(w.polesIn(0, 1, SpanRules{2, {}}), 1u);
}

}  // namespace
}  // namespace lidarcal::watch
