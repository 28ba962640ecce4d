// SPDX-License-Identifier: BSD-3-Clause
// The watcher's error rates measured over many simulated drives (label slow): the false alarms
// on clean drives against the rate set, and how often an offset is found.
#include <cmath>

#include <gtest/gtest.h>

#include "drive.hpp"

namespace lidarcal::watch {
namespace {

/// The tests of `kind` made on clean drives of `scene`, seeds [first, first + drives): how many
/// rejected the (true) model, against the sum of their levels (the number expected) and its
/// variance.
struct Rejections {
  std::size_t tests = 0, rejected = 0;
  double expected = 0.0, variance = 0.0;
};
Rejections cleanDrives(const Scene& scene, watch::Test kind, std::uint64_t first, int drives,
                       int bias_replicas = CheckSettings{}.bias_replicas) {
  WatchSettings s = test::watchSettings(scene, Mode::watch);
  s.false_alarms.per_unit = 20.0;  // alarms often enough to count: each test's level 20 x exposure
  s.check.bias_replicas = bias_replicas;
  Rejections r;
  for (std::uint64_t seed = first; seed < first + static_cast<std::uint64_t>(drives); ++seed) {
    WatchSink sink;
    sink.check = [&](const CheckEvent& e) {
      if (e.test != kind) return;
      ++r.tests;
      r.expected += e.level;
      r.variance += e.level * (1.0 - e.level);
      r.rejected += e.exceeds;
    };
    Engine engine(s, test::trueModel(scene), FitExecution::at_scan, sink);
    test::driveThrough(engine, scene, seed);
  }
  return r;
}

TEST(WatchRates, ChangeTestsOnCleanDrivesRejectAtTheRateSet) {
  // 200 drives of 30 m among thin poles at 20 false alarms per km: the change tests that reject
  // the model must number the sum of their levels, within four standard deviations. They test
  // the fitted shifts whatever the replicas, which only add time here.
  const Rejections r = cleanDrives(test::drivingScene("driving_small_poles", 1000),
                                   watch::Test::change, 1000, 200, 0);
  RecordProperty("tests", static_cast<int>(r.tests));
  RecordProperty("rejected", static_cast<int>(r.rejected));
  RecordProperty("expected", std::to_string(r.expected));
  EXPECT_GE(r.tests, 800u);
  EXPECT_NEAR(static_cast<double>(r.rejected), r.expected, 4.0 * std::sqrt(r.variance))
      << r.rejected << " of " << r.tests << " tests rejected, " << r.expected << " expected";
}

TEST(WatchRates, TheBaselineTestOnCleanDrivesRejectsAtTheRateSet) {
  // The baseline's test against zero, once per drive (200 drives of 18 m among 0.1 m poles),
  // without the fit's own bias taken out: it holds when the fit is unbiased, as it is for poles
  // seen by many beams.
  const Rejections r = cleanDrives(test::drivingScene("driving_large_poles", 600),
                                   watch::Test::absolute, 1000, 200, 0);
  RecordProperty("rejected", static_cast<int>(r.rejected));
  RecordProperty("expected", std::to_string(r.expected));
  EXPECT_GE(r.tests, 190u);
  EXPECT_NEAR(static_cast<double>(r.rejected), r.expected, 4.0 * std::sqrt(r.variance))
      << r.rejected << " of " << r.tests << " tests rejected, " << r.expected << " expected";
}

TEST(WatchRates, AmongThinPolesTheBaselineTestHoldsItsRateWithTheFitsBiasTakenOut) {
  // Thin poles bias the check's own fit, and without its bias taken out the baseline's test
  // against zero rejects about 1.5 times its level over these 200 drives (88 where 60 are
  // expected); by default replicas of each baseline check estimate that bias.
  const Rejections r =
      cleanDrives(test::drivingScene("driving_small_poles", 560), watch::Test::absolute, 1000, 200);
  RecordProperty("rejected", static_cast<int>(r.rejected));
  RecordProperty("expected", std::to_string(r.expected));
  EXPECT_GE(r.tests, 190u);
  EXPECT_NEAR(static_cast<double>(r.rejected), r.expected, 4.0 * std::sqrt(r.variance))
      << r.rejected << " of " << r.tests << " tests rejected, " << r.expected << " expected";
}

/// Drives with `offset` injected at scan 900: in how many is it found within 200 scans (6 m)?
int found(const Scene& scene, const char* change_text, int drives) {
  const RangeChange change = parseRangeChange(change_text);
  int n = 0;
  for (int k = 0; k < drives; ++k) {
    bool early = false, hit = false;
    WatchSink sink;
    sink.check = [&](const CheckEvent& e) {
      if (!e.alarm) return;
      if (e.decided_at < change.from_scan) early = true;
      if (e.decided_at >= change.from_scan && e.decided_at <= change.from_scan + 200) hit = true;
    };
    Engine engine(test::watchSettings(scene, Mode::watch), test::trueModel(scene),
                  FitExecution::at_scan, sink);
    test::driveThrough(engine, scene, 2000 + static_cast<std::uint64_t>(k), change);
    n += hit && !early;
  }
  return n;
}

TEST(WatchRates, OffsetsOf20And10MmAreFoundWithinTwoChecksAmongThinPoles) {
  const Scene scene = test::drivingScene("driving_small_poles", 1200);
  EXPECT_GE(found(scene, "20@900", 20), 19);
  EXPECT_GE(found(scene, "10@900", 20), 15);
}

}  // namespace
}  // namespace lidarcal::watch
