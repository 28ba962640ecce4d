// SPDX-License-Identifier: BSD-3-Clause
// The watcher on its own threads, as the nodes run it: scans offered without waiting, results
// read while it works.
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "drive.hpp"
#include "watch/diagnostics.hpp"
#include "watch/live_watcher.hpp"

namespace lidarcal::watch {
namespace {

/// Offers every scan, waiting while the queue is full (a replay, not a robot), then waits until
/// the watcher has seen them all.
void offerAll(LiveWatcher& w, const Scene& scene, std::uint64_t seed, const RangeChange& change) {
  const auto stops = simulation::planStops(scene, seed);
  for (std::size_t i = 0; i < stops.size(); ++i) {
    io::RawScan scan = test::driveScan(scene, stops, i, seed, change);
    while (!w.offer(scan)) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  while (w.state().scans < stops.size()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
}

TEST(LiveWatcher, FindsAChangeWhileTheCallerNeverWaits) {
  const Scene scene = test::drivingScene("driving_large_poles", 1500);
  LiveWatcher w(test::watchSettings(scene, Mode::learn), test::trueModel(scene), 16);
  EXPECT_EQ(w.modelVersion(), 1u);
  offerAll(w, scene, 91, parseRangeChange("20@900"));
  // Fits finish on their own thread; give the last ones time to land.
  for (int k = 0; k < 200 && w.modelVersion() == 1; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const std::vector<CheckEvent> checks = w.takeChecks();
  std::size_t alarms_before = 0, alarms_after = 0;
  for (const auto& c : checks) (c.decided_at < 900 ? alarms_before : alarms_after) += c.alarm;
  EXPECT_EQ(alarms_before, 0u);
  EXPECT_GE(alarms_after, 1u);
  EXPECT_EQ(w.modelVersion(), 2u) << w.state().message;
  EXPECT_TRUE(w.takeChecks().empty());  // taken once
  const DiagnosticReport r =
      diagnosticReport(w.state(), w.model().get(), test::watchSettings(scene, Mode::learn), 0);
  EXPECT_FALSE(r.message.empty());
  EXPECT_EQ(r.values.front().first, "mode");
}

TEST(LiveWatcher, CountsTheScansItCouldNotTake) {
  const Scene scene = test::drivingScene("driving_large_poles", 200);
  LiveWatcher w(test::watchSettings(scene, Mode::watch), test::trueModel(scene), 2);
  const auto stops = simulation::planStops(scene, 92);
  const io::RawScan scan = test::driveScan(scene, stops, 0, 92);
  std::size_t refused = 0;
  for (int k = 0; k < 200; ++k) refused += !w.offer(scan);  // far faster than detection
  EXPECT_GT(refused, 0u);
  EXPECT_EQ(w.dropped(), refused);
}

}  // namespace
}  // namespace lidarcal::watch
