// Sightings from the coordinates the detection kept equal those from reading the scans again
// (issue 19: calibrate and run read every scan once).

#include <gtest/gtest.h>

#include <cmath>

#include "detectors/sequence_detector.hpp"
#include "io/sequence.hpp"
#include "pipeline/collect_sightings.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

TEST(CollectSightings, KeptInlierCoordinatesGiveTheSightingsOfASecondRead) {
  const io::Sequence seq = io::openSequence(test::sourceDir() / "data/example/scans");
  const detectors::SequenceDetections kept = detectors::detectSequence(seq, detectors::SequenceDetectionConfig{});
  std::size_t reads = 0;
  const detectors::ScanLoader counting = [&](std::size_t i) {
    ++reads;
    return io::readScan(seq.scans.path(i));
  };
  const LandmarkObservations from_kept = pipeline::toLandmarkObservations(seq, kept, counting);
  EXPECT_EQ(reads, 0u);  // nothing read again

  detectors::SequenceDetections stripped = kept;
  for (auto& scan : stripped.scans)
    for (auto& d : scan.detections) d.inlier_xyi.clear();
  const LandmarkObservations from_files = pipeline::toLandmarkObservations(seq, stripped, counting);
  EXPECT_GT(reads, 0u);

  ASSERT_FALSE(from_kept.sightings.empty());
  ASSERT_EQ(from_kept.sightings.size(), from_files.sightings.size());
  for (std::size_t k = 0; k < from_kept.sightings.size(); ++k) {
    const auto& a = from_kept.sightings[k];
    const auto& b = from_files.sightings[k];
    EXPECT_EQ(a.scan, b.scan);
    EXPECT_EQ(a.landmark, b.landmark);
    ASSERT_EQ(a.beams.size(), b.beams.size());
    for (std::size_t j = 0; j < a.beams.size(); ++j) {
      EXPECT_EQ(a.beams[j].angle_rad, b.beams[j].angle_rad);
      EXPECT_EQ(a.beams[j].range_m, b.beams[j].range_m);
      EXPECT_EQ(a.beams[j].beam, b.beams[j].beam);
      // Intensity as recorded, or NaN (none) on both sides.
      EXPECT_TRUE(a.beams[j].intensity == b.beams[j].intensity ||
                  (std::isnan(a.beams[j].intensity) && std::isnan(b.beams[j].intensity)));
    }
  }
}

}  // namespace
}  // namespace lidarcal
