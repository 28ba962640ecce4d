// SPDX-License-Identifier: BSD-3-Clause
// Sightings from the coordinates the detection kept equal those from reading the scans again
// (calibrate and run read every scan once), and come by landmark within a scan whatever the
// detector's order.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "detectors/sequence_detector.hpp"
#include "detectors/sightings.hpp"
#include "io/sequence.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

/// The same sightings in the same order: scan, landmark and every reading (intensity as
/// recorded, or NaN, none, on both sides).
void expectSameSightings(const LandmarkObservations& x, const LandmarkObservations& y) {
  ASSERT_EQ(x.sightings.size(), y.sightings.size());
  for (std::size_t k = 0; k < x.sightings.size(); ++k) {
    const auto& a = x.sightings[k];
    const auto& b = y.sightings[k];
    EXPECT_EQ(a.scan, b.scan);
    EXPECT_EQ(a.landmark, b.landmark);
    ASSERT_EQ(a.beams.size(), b.beams.size());
    for (std::size_t j = 0; j < a.beams.size(); ++j) {
      EXPECT_EQ(a.beams[j].angle_rad, b.beams[j].angle_rad);
      EXPECT_EQ(a.beams[j].range_m, b.beams[j].range_m);
      EXPECT_EQ(a.beams[j].beam, b.beams[j].beam);
      EXPECT_TRUE(a.beams[j].intensity == b.beams[j].intensity ||
                  (std::isnan(a.beams[j].intensity) && std::isnan(b.beams[j].intensity)));
    }
  }
}

TEST(Sightings, KeptInlierCoordinatesGiveTheSightingsOfASecondRead) {
  const io::Sequence seq = io::openSequence(test::sourceDir() / "data/example/scans");
  const detectors::SequenceDetections kept =
      detectors::detectSequence(seq, detectors::SequenceDetectionConfig{});
  std::size_t reads = 0;
  const detectors::ScanLoader counting = [&](std::size_t i) {
    ++reads;
    return io::readScan(seq.scans.path(i));
  };
  const LandmarkObservations from_kept = detectors::toLandmarkObservations(seq, kept, counting);
  EXPECT_EQ(reads, 0u);  // nothing read again

  detectors::SequenceDetections stripped = kept;
  for (auto& scan : stripped.scans)
    for (auto& d : scan.detections) d.inlier_xyi.clear();
  const LandmarkObservations from_files =
      detectors::toLandmarkObservations(seq, stripped, counting);
  EXPECT_GT(reads, 0u);

  ASSERT_FALSE(from_kept.sightings.empty());
  expectSameSightings(from_kept, from_files);
}

TEST(Sightings, TheSightingsOfAScanComeByLandmarkWhateverTheDetectorsOrder) {
  const io::Sequence seq = io::openSequence(test::sourceDir() / "data/example/scans");
  const detectors::SequenceDetections det =
      detectors::detectSequence(seq, detectors::SequenceDetectionConfig{});
  detectors::SequenceDetections reversed = det;
  // scans with two poles or more, whose detections now come the other way round
  std::size_t turned = 0;
  for (std::size_t i = 0; i < reversed.scans.size(); ++i) {
    auto& d = reversed.scans[i].detections;
    auto& ids = reversed.association.ids.at(i);
    ASSERT_EQ(d.size(), ids.size());
    std::reverse(d.begin(), d.end());
    std::reverse(ids.begin(), ids.end());
    turned += d.size() > 1 ? 1 : 0;
  }
  ASSERT_GT(turned, 0u);
  const LandmarkObservations a = detectors::toLandmarkObservations(seq, det);
  const LandmarkObservations b = detectors::toLandmarkObservations(seq, reversed);
  expectSameSightings(a, b);
  ASSERT_EQ(a.sightings.size(), b.sightings.size());
  for (std::size_t k = 0; k < a.sightings.size(); ++k) {
    EXPECT_EQ(a.sightings[k].bearing_rad, b.sightings[k].bearing_rad);
    if (k > 0 && a.sightings[k].scan == a.sightings[k - 1].scan) {
      EXPECT_LT(a.sightings[k - 1].landmark, a.sightings[k].landmark);
    }
  }
}

TEST(Sightings, APointReadsAlongItsBeamAndAZeroIntensityIsNone) {
  const BeamReading r = detectors::beamReading(3.0f, 4.0f, 0.0f, 7);
  EXPECT_NEAR(r.range_m, 5.0, 1e-12);
  EXPECT_NEAR(r.angle_rad, std::atan2(4.0, 3.0), 1e-12);
  EXPECT_EQ(r.beam, 7u);
  EXPECT_TRUE(std::isnan(r.intensity));
  EXPECT_EQ(detectors::beamReading(0.0f, -2.0f, 12.5f, 0).intensity, 12.5);
  io::Scan scan;
  scan.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
  pcl::PointXYZI p;
  p.x = std::nanf("");
  p.y = 1.0f;
  scan.cloud->push_back(p);
  EXPECT_FALSE(detectors::pointReading(scan, 0).has_value());  // no return
}

}  // namespace
}  // namespace lidarcal
