// SPDX-License-Identifier: BSD-3-Clause
// The field watcher end to end on simulated drives whose truth the test sets: the scene's own
// sensor as the model, changes injected from a chosen scan on.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "drive.hpp"

namespace lidarcal::watch {
namespace {

using test::drivingScene;
using test::trueModel;
using test::watchSettings;

struct Recorded {
  std::vector<CheckEvent> checks;
  std::vector<RefitEvent> refits;
  WatchSink sink() {
    return {[this](const CheckEvent& e) { checks.push_back(e); },
            [this](const RefitEvent& e) { refits.push_back(e); }};
  }
  std::size_t alarmsBefore(std::size_t scan) const {
    std::size_t n = 0;
    for (const auto& c : checks) n += c.alarm && c.decided_at < scan;
    return n;
  }
  const CheckEvent* firstAlarmFrom(std::size_t scan) const {
    for (const auto& c : checks)
      if (c.alarm && c.decided_at >= scan) return &c;
    return nullptr;
  }
};

TEST(WatchEngine, CleanDrivesRaiseNoAlarmAndTestTheModel) {
  const Scene scene = drivingScene("driving_large_poles", 1200);
  for (std::uint64_t seed : {21u, 22u, 23u}) {
    SCOPED_TRACE(seed);
    Recorded r;
    Engine e(watchSettings(scene, Mode::watch), trueModel(scene), FitExecution::at_scan, r.sink());
    test::driveThrough(e, scene, seed);
    EXPECT_EQ(e.state().alarms, 0u);
    EXPECT_GE(e.state().checks, 5u);  // the absolute test and change tests were made
    EXPECT_EQ(e.state().level, Health::ok) << e.state().message;
    EXPECT_LE(e.state().sightings, e.state().scans * 10);
    // The fit's own bias is estimated where a shift is tested against zero (the baseline), not
    // for the change tests, which cancel it.
    const int replicas = CheckSettings{}.bias_replicas;
    for (const auto& c : r.checks) {
      if (!c.check.status.ok()) continue;
      const bool against_zero = c.test == watch::Test::baseline || c.test == watch::Test::absolute;
      EXPECT_EQ(c.check.bias_replicas, against_zero ? replicas : 0) << c.decided_at;
    }
  }
}

TEST(WatchEngine, An20MmOffsetIsFoundAtTheNextCheckAndNotBefore) {
  const Scene scene = drivingScene("driving_large_poles", 1500);
  const RangeChange change = parseRangeChange("20@900");
  Recorded r;
  Engine e(watchSettings(scene, Mode::watch), trueModel(scene), FitExecution::at_scan, r.sink());
  test::driveThrough(e, scene, 31, change);
  EXPECT_EQ(r.alarmsBefore(change.from_scan), 0u);
  const CheckEvent* a = r.firstAlarmFrom(change.from_scan);
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->test, watch::Test::change);
  // Within two checks' travel (3 m each at 3 cm a scan: 100 scans).
  EXPECT_LE(a->decided_at, change.from_scan + 200);
  // The shift is the offset in corrected distance, 20 mm / f'(d), within 4 standard errors.
  const double d = a->check.distance_m[0];
  const double expected = 0.020 / scene.sensor.range.bias.derivative(d);
  EXPECT_NEAR(a->check.shift_m[0], expected, 4.0 * a->check.shift_se_m[0] + 0.002);
  EXPECT_EQ(e.state().level, Health::error);
}

TEST(WatchEngine, AModelOfAnotherSensorFailsItsBaseline) {
  const Scene scene = drivingScene("driving_large_poles", 700);
  for (const Mode mode : {Mode::watch, Mode::learn}) {
    Recorded r;
    Engine e(watchSettings(scene, mode), trueModel(scene), FitExecution::at_scan, r.sink());
    test::driveThrough(e, scene, 41, parseRangeChange("30@0"));
    ASSERT_FALSE(r.checks.empty());
    const auto absolute = std::find_if(r.checks.begin(), r.checks.end(), [](const CheckEvent& c) {
      return c.test == watch::Test::absolute;
    });
    ASSERT_NE(absolute, r.checks.end());
    EXPECT_TRUE(absolute->alarm);
    if (mode == Mode::watch) {
      EXPECT_EQ(e.state().level, Health::error);
      EXPECT_NE(e.state().message.find("does not describe this sensor"), std::string::npos);
    }
    // In learn mode the checks after the failed baseline are tested against zero again (the
    // switch test), so they too have the fit's bias estimated; in watch mode nothing tests them.
    std::size_t after = 0;
    for (auto c = absolute + 1; c != r.checks.end(); ++c) {
      if (!c->check.status.ok() || c->model_version != absolute->model_version) continue;
      ++after;
      EXPECT_EQ(c->check.bias_replicas, mode == Mode::learn ? CheckSettings{}.bias_replicas : 0);
    }
    EXPECT_GE(after, 1u);
  }
}

TEST(WatchEngine, LearnModeSwitchesAfterAChangeToAModelOfTheChangedSensor) {
  const Scene scene = drivingScene("driving_large_poles", 2000);
  const RangeChange change = parseRangeChange("20@900");
  Recorded r;
  Engine e(watchSettings(scene, Mode::learn), trueModel(scene), FitExecution::at_scan, r.sink());
  test::driveThrough(e, scene, 51, change);
  std::size_t switches = 0;
  for (const auto& f : r.refits) {
    if (!f.decision.adopt) continue;
    ++switches;
    EXPECT_GE(f.stretch.first_scan + 100, change.from_scan);  // learnt from after the change
    // The new model reads 20 mm longer than the old one, within 4 of its standard errors.
    const CalibrationModel& m = *f.candidate;
    for (double d : referenceDistances(m)) {
      const double se = std::sqrt(calibration::biasCovariance(m, {d})(0, 0));
      EXPECT_NEAR(m.model.bias(d) - scene.sensor.range.bias(d), 0.020, 4.0 * se + 0.001) << d;
    }
  }
  EXPECT_EQ(switches, 1u);
  EXPECT_EQ(e.state().model_version, 2u);
  EXPECT_NE(e.state().level, Health::error) << e.state().message;
}

TEST(WatchEngine, LearnModeNeverSwitchesOnACleanDrive) {
  const Scene scene = drivingScene("driving_large_poles", 1500);
  Recorded r;
  Engine e(watchSettings(scene, Mode::learn), trueModel(scene), FitExecution::at_scan, r.sink());
  test::driveThrough(e, scene, 61);
  EXPECT_EQ(e.state().switches, 0u);
  EXPECT_EQ(e.state().model_version, 1u);
}

TEST(WatchEngine, LearnModeWithoutAModelAdoptsOneOnceItIsDetermined) {
  const Scene scene = drivingScene("driving_large_poles", 1200);
  Recorded r;
  Engine e(watchSettings(scene, Mode::learn), nullptr, FitExecution::at_scan, r.sink());
  EXPECT_EQ(e.model(), nullptr);
  EXPECT_EQ(e.state().level, Health::warn);
  test::driveThrough(e, scene, 71);
  ASSERT_NE(e.model(), nullptr) << "no model adopted";
  const CalibrationModel& m = *e.model();
  for (double d : referenceDistances(m)) {
    const double se = std::sqrt(calibration::biasCovariance(m, {d})(0, 0));
    EXPECT_LE(se, watchSettings(scene, Mode::learn).learn.max_standard_error_m);
    EXPECT_NEAR(m.model.bias(d), scene.sensor.range.bias(d), 4.0 * se + 0.001) << d;
  }
}

TEST(WatchEngine, MemoryIsBoundedByTheWindowWhateverTheDrive) {
  Scene scene = drivingScene("driving_large_poles", 4000);
  WatchSettings s = watchSettings(scene, Mode::watch);
  s.check.every_m = 1e9;  // no fits: this is about what the engine holds
  s.check.max_scans = 300;
  s.association.forget_landmarks_after_stops = 300;
  Engine e(s, trueModel(scene), FitExecution::at_scan);
  const auto stops = simulation::planStops(scene, 81);
  std::size_t most_sightings = 0, most_tracks = 0;
  for (std::size_t i = 0; i < stops.size(); ++i) {
    e.observe(test::driveScan(scene, stops, i, 81));
    most_sightings = std::max(most_sightings, e.state().sightings);
    most_tracks = std::max(most_tracks, e.state().tracks);
    if (i == 1000) {
      EXPECT_GT(e.state().sightings, 300u);
    }
  }
  // 300 scans of at most the scene's poles, and a track per pole or object seen lately.
  EXPECT_LE(most_sightings, 300 * (scene.landmarks.size() + scene.clutter.size()));
  EXPECT_LE(most_tracks, 4 * (scene.landmarks.size() + scene.clutter.size()));
}

TEST(WatchEngine, RefusesAModelItCannotCheck) {
  const Scene scene = drivingScene("driving_large_poles", 10);
  auto m = std::make_shared<CalibrationModel>(*trueModel(scene));
  m->alpha_covariance.clear();
  EXPECT_THROW(Engine(watchSettings(scene, Mode::watch), m, FitExecution::at_scan),
               std::invalid_argument);
  EXPECT_THROW(Engine(watchSettings(scene, Mode::watch), nullptr, FitExecution::at_scan),
               std::invalid_argument);
}

}  // namespace
}  // namespace lidarcal::watch
