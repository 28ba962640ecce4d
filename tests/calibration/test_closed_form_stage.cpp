// SPDX-License-Identifier: BSD-3-Clause
// The closed-form stage's pieces against answers the test controls: noise-free readings of a
// known circle give the exact landmark-stop distance, readings at one distance group into one
// batch per (stop, landmark, beam), the radius is the known one or the median of the fits.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "calibration/closed_form_stage.hpp"

namespace lidarcal {
namespace {

/// Stops along y = 0 looking along +y at a pole of radius r at (cx, cy); per stop `scans`
/// identical scans of the central beam, reading exactly the distance to the circle.
LandmarkObservations poleSeenFromALine(double cx, double cy, double r, int stops, int scans) {
  LandmarkObservations obs;
  std::size_t scan = 0;
  for (int k = 0; k < stops; ++k) {
    const Pose2 p{0.5 * k, 0.0, M_PI / 2};
    obs.commanded.push_back(p);
    const double dx = cx - p.x_m, dy = cy - p.y_m;
    const double bearing = std::atan2(dy, dx) - p.yaw_rad;
    for (int s = 0; s < scans; ++s) {
      Sighting si;
      si.stop = static_cast<std::size_t>(k);
      si.scan = scan++;
      si.landmark = 1;
      si.bearing_rad = bearing;
      si.radius_m = r + 0.001 * s;
      si.beams.push_back({bearing, std::hypot(dx, dy) - r, 100});
      obs.sightings.push_back(si);
    }
  }
  return obs;
}

TEST(ClosedFormStage, NoiseFreeReadingsOfAKnownCircleGiveTheirExactDistances) {
  const double cx = 1.0, cy = 3.0, r = 0.05;
  const LandmarkObservations obs = poleSeenFromALine(cx, cy, r, 4, 3);
  calibration::LandmarkEstimate l;
  l.id = 1;
  l.x_m = cx;
  l.y_m = cy;
  for (const bool per_scan : {false, true}) {
    SCOPED_TRACE(per_scan);
    const auto pairs = calibration::closedFormPairs(obs, {l}, r, per_scan);
    // per scan, or averaged per (stop, part): three scans a stop, one part each
    ASSERT_EQ(pairs.size(), 12u);
    for (const auto& p : pairs) {
      EXPECT_NEAR(p.d_m, p.y_m, 1e-9);
      EXPECT_GE(p.part, 0);
      EXPECT_LE(p.part, 2);
    }
  }
  // A landmark the triangulation did not place gives no pair.
  l.status = calibration::TriangulationStatus::too_few_stops;
  EXPECT_TRUE(calibration::closedFormPairs(obs, {l}, r, true).empty());
}

TEST(ClosedFormStage, ReadingsAtOneDistanceFormOneBatchPerStopLandmarkAndBeam) {
  const LandmarkObservations obs = poleSeenFromALine(1.0, 3.0, 0.05, 4, 3);
  const auto batches = calibration::constantDistanceBatches(obs);
  ASSERT_EQ(batches.size(), 4u);
  for (const auto& b : batches) {
    ASSERT_EQ(b.size(), 3u);
    EXPECT_EQ(b[0], b[1]);
    EXPECT_EQ(b[1], b[2]);
  }
}

TEST(ClosedFormStage, TheRadiusIsTheKnownOneElseTheMedianOfTheFits) {
  // fitted radii 0.050, 0.051, 0.052
  LandmarkObservations obs = poleSeenFromALine(1.0, 3.0, 0.05, 2, 3);
  EXPECT_NEAR(calibration::landmarkRadius(obs), 0.051, 1e-12);
  obs.landmark_radius_m = 0.04;
  EXPECT_EQ(calibration::landmarkRadius(obs), 0.04);
}

TEST(ClosedFormStage, AnOrderIsAdmissibleOnlyWhenItInvertsTheReadingWindow) {
  const calibration::Admissible ok = calibration::invertibleOver(0.1, 10.0);
  EXPECT_TRUE(ok({0.01, 1.02}));
  EXPECT_FALSE(ok({0.01, -1.0}));  // falls with distance
  EXPECT_FALSE(ok({0.0}));         // order 0: no distance to invert to
}

TEST(ClosedFormStage, TheResidualRmsIsZeroOnTheCurveAndTheOffsetOffIt) {
  const BiasPolynomial f{{0.02, 1.01}};
  const std::vector<double> d = {1.0, 2.0, 3.0};
  std::vector<double> y;
  for (double x : d) y.push_back(f(x));
  EXPECT_NEAR(calibration::rmsResidual(f, d, y), 0.0, 1e-15);
  for (double& v : y) v += 0.003;
  EXPECT_NEAR(calibration::rmsResidual(f, d, y), 0.003, 1e-12);
  EXPECT_EQ(calibration::rmsResidual(f, {}, {}), 0.0);
}

}  // namespace
}  // namespace lidarcal
