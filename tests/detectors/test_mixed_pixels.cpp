// SPDX-License-Identifier: BSD-3-Clause
// The readings beside a pole that only a mixed pixel puts between it and its background, and
// the check that no nearby scan sees a surface there.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "common/rng.hpp"
#include "detectors/mixed_pixels.hpp"
#include "detectors/sequence_detector.hpp"
#include "detectors/sightings.hpp"
#include "io/sequence.hpp"
#include "io/simulation_truth.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

/// A scan of 360 one-degree beams: a wall 3 m away across the view, ranges `r` on beams 10-13.
io::Scan wallScan(const std::vector<double>& r) {
  io::Scan scan;
  scan.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
  for (int b = 0; b < 360; ++b) {
    const double a = b * M_PI / 180.0;
    // walls at x = +-3 m
    double range = std::abs(std::cos(a)) > 0.2 ? 3.0 / std::abs(std::cos(a)) : 15.0;
    if (b >= 10 && b < 10 + static_cast<int>(r.size())) range = r[static_cast<std::size_t>(b - 10)];
    pcl::PointXYZI p;
    p.x = static_cast<float>(range * std::cos(a));
    p.y = static_cast<float>(range * std::sin(a));
    p.z = 0.0f;
    p.intensity = 0.0f;
    scan.cloud->push_back(p);
  }
  return scan;
}

TEST(MixedPixels, OnlyAReadingBetweenThePoleAndTheWallBehindItIsAMixedPixelCandidate) {
  const detectors::DetectionConfig dc;  // t(r) = 0.01 + 0.005 r^2
  const double radius = 0.0275;
  // A pole at 1 m on beams 10-12, beam 13 beside it; the wall behind reads about 3.05 m there.
  const auto beside = [&](double reading) {
    return detectors::readingBetweenPoleAndBackground(wallScan({1.00, 0.99, 1.00, reading}), 12, +1,
                                                      radius, dc);
  };
  const auto mid = beside(2.0);
  ASSERT_TRUE(mid.has_value());
  EXPECT_EQ(mid->beam, 13u);
  EXPECT_NEAR(mid->range_m, 2.0, 1e-6);
  EXPECT_NEAR(mid->angle_rad, 13.0 * M_PI / 180.0, 1e-6);
  EXPECT_FALSE(beside(1.03).has_value());  // the pole itself, seen at its flank
  EXPECT_FALSE(beside(3.0 / std::cos(13.0 * M_PI / 180.0)).has_value());  // the wall
  EXPECT_FALSE(beside(2.95).has_value());                                 // within 3 t of the wall
  EXPECT_TRUE(beside(2.70).has_value());
  // On the other side (beam 9 and below), the wall extended to beam 9 is the background.
  EXPECT_FALSE(
      detectors::readingBetweenPoleAndBackground(wallScan({1.00, 0.99, 1.00}), 10, -1, radius, dc)
          .has_value());
  // Beams not evenly spaced in angle (a return missing from a dense cloud) are not judged.
  io::Scan gap = wallScan({1.00, 0.99, 1.00, 2.0});
  gap.cloud->erase(gap.cloud->begin() + 14);
  EXPECT_FALSE(detectors::readingBetweenPoleAndBackground(gap, 12, +1, radius, dc).has_value());
}

TEST(MixedPixels, AScanSeesAPointOnlyWhereOneOfItsReturnsReadsItsDistance) {
  // The wall scan from a pose at (1, 2) turned by 0.3 rad: every return's own world point is
  // seen, a point 0.2 m nearer along the same beam is not, and the tolerance decides in between.
  const io::Scan scan = wallScan({});
  const detectors::PolarScan polar = detectors::polarScan(scan);
  ASSERT_EQ(polar.angle_rad.size(), 360u);
  EXPECT_TRUE(std::is_sorted(polar.angle_rad.begin(), polar.angle_rad.end()));
  const Pose2 from{1.0, 2.0, 0.3};
  // beams where the wall is square to the beam (or far): neighbours read alike
  for (int b : {0, 90, 175, 355}) {
    SCOPED_TRACE(b);
    const auto& p = (*scan.cloud)[static_cast<std::size_t>(b)];
    const double a = from.yaw_rad + std::atan2(p.y, p.x), r = std::hypot(p.x, p.y);
    EXPECT_TRUE(detectors::seesPoint(polar, from, from.x_m + r * std::cos(a),
                                     from.y_m + r * std::sin(a), 0.01));
    EXPECT_FALSE(detectors::seesPoint(polar, from, from.x_m + (r - 0.2) * std::cos(a),
                                      from.y_m + (r - 0.2) * std::sin(a), 0.1));
    EXPECT_TRUE(detectors::seesPoint(polar, from, from.x_m + (r - 0.2) * std::cos(a),
                                     from.y_m + (r - 0.2) * std::sin(a), 0.3));
  }
  EXPECT_FALSE(detectors::seesPoint(detectors::PolarScan{}, from, 0.0, 0.0, 1.0));  // no returns
}

/// Sightings of a simulated drive among thin poles, with the mixed-pixel candidates and without,
/// and its truth.
struct Drive {
  LandmarkObservations obs, inliers_only;
  io::SimulationTruth truth;
};

Drive simulateDrive(const test::TempDir& dir, const std::string& name, double mixed_fraction,
                    int seed) {
  nlohmann::json s = nlohmann::json::parse(
      test::readFile(test::sourceDir() / "data/scenes/driving_small_poles.json"));
  if (mixed_fraction > 0.0) s["sensor"]["effects"] = {{"mixed_pixel_fraction", mixed_fraction}};
  test::writeFile(dir / (name + ".json"), s.dump(1));
  const auto r =
      test::runCli("simulate -q --scene " + (dir / (name + ".json")).string() + " --out " +
                   (dir / name).string() + " --seed " + std::to_string(seed));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const io::Sequence seq = io::openSequence(dir / name / "scans");
  const auto det = detectors::detectSequence(seq, detectors::SequenceDetectionConfig{});
  detectors::SightingOptions with;
  with.mixed_pixel_candidates = true;
  return {detectors::toLandmarkObservations(seq, det, with),
          detectors::toLandmarkObservations(seq, det), io::loadTruth(dir / name / "truth.json")};
}

/// The sightings' readings that are no inlier of their circle (those beside it), split by truth
/// into mixed pixels (the beam hit a pole and reads 5 noise deviations or more beyond it) and
/// others.
std::pair<int, int> besideReadings(const Drive& d) {
  int mixed = 0, other = 0;
  const RangeModel& m = d.truth.truth.scene.sensor.range;
  for (std::size_t k = 0; k < d.obs.sightings.size(); ++k) {
    const auto& with = d.obs.sightings[k].beams;
    const auto& without = d.inliers_only.sightings.at(k).beams;
    for (const auto& b : with) {
      if (std::any_of(without.begin(), without.end(),
                      [&](const BeamReading& w) { return w.beam == b.beam; }))
        continue;
      const io::TrueRange& t = d.truth.at(d.obs.sightings[k].scan, b.beam);
      const bool on_pole = t.target == io::TargetKind::landmark;
      const bool is_mixed =
          on_pole && b.range_m - m.bias(t.range_m) > 5.0 * m.noise.stddev(t.range_m, m.bias);
      (is_mixed ? mixed : other) += 1;
    }
  }
  return {mixed, other};
}

TEST(MixedPixels, TheReadingsKeptBesideThinPolesAreTheMixedPixels) {
  // A drive among thin poles (one to three beams per pole), 5-10 % of the beams at a pole's edge
  // reading somewhere between it and the background; the detector leaves those readings out.
  // The fraction and the simulator's seed come from a seed this test does not read. Every
  // reading kept beside a pole must be a mixed pixel by the simulator's truth; without mixed
  // pixels (the same seed) what is seen beside the poles (another pole or a wall corner behind
  // them, seen again from the next poses) must not be kept.
  test::TempDir dir;
  auto rng = makeRng(20261128, 3);
  const double fraction = std::uniform_real_distribution<double>(0.05, 0.10)(rng);
  const int seed = std::uniform_int_distribution<int>(100, 100000)(rng);
  for (const double f : {fraction, 0.0}) {
    const auto [mixed, other] =
        besideReadings(simulateDrive(dir, f > 0.0 ? "mixed" : "clean", f, seed));
    EXPECT_EQ(other, 0) << "fraction " << f << ", seed " << seed;
    std::printf(
        "fraction %.3f, seed %d: %d mixed pixels kept beside the poles, %d other readings\n", f,
        seed, mixed, other);
    if (f > 0.0) {
      // About 3,000 readings at a pole's edge in 300 scans, so 150-300 mixed pixels; about a
      // quarter lie beside a detected pole (at 10 %: 77 of 298; the others leave too few beams
      // on their pole for a detection).
      EXPECT_GE(mixed, 20) << "fraction " << f << ", seed " << seed;
    } else {
      EXPECT_EQ(mixed, 0);
    }
  }
}

}  // namespace
}  // namespace lidarcal
