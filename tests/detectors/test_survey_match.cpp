// SPDX-License-Identifier: BSD-3-Clause
// Surveyed landmarks matched to detected ones: the closest pairs first, one to one, within the
// gate; an entry without a detected landmark near it gets id 0.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "detectors/survey_match.hpp"

namespace lidarcal {
namespace {

detectors::Landmark detected(int id, double x, double y) {
  detectors::Landmark l;
  l.id = id;
  l.x_m = x;
  l.y_m = y;
  return l;
}

TEST(SurveyMatch, TheClosestPairsMatchFirstOneToOneWithinTheGate) {
  // Surveyed 0 is 0.1 m from detected 7 and 0.3 m from detected 8; surveyed 1 is 0.05 m from
  // detected 7 and 0.34 m from detected 8; surveyed 2 has nothing within kSurveyGateM.
  const std::vector<ReferenceLandmark> surveyed = {{0.0, 0.0, {}}, {0.15, 0.0, {}}, {5.0, 5.0, {}}};
  const std::vector<detectors::Landmark> found = {detected(7, 0.1, 0.0), detected(8, 0.0, 0.3),
                                                  detected(9, 5.6, 5.0)};
  const auto m = detectors::matchSurvey(surveyed, found);
  ASSERT_EQ(m.size(), 3u);
  for (std::size_t s = 0; s < m.size(); ++s) EXPECT_EQ(m[s].entry, s);
  EXPECT_EQ(m[1].id, 7);  // the closest pair of all (0.05 m) first
  EXPECT_NEAR(m[1].distance_m, 0.05, 1e-12);
  EXPECT_EQ(m[0].id, 8);  // 7 is taken: the next one within the gate
  EXPECT_NEAR(m[0].distance_m, 0.3, 1e-12);
  EXPECT_EQ(m[2].id, 0);  // 0.6 m away: beyond the gate
  EXPECT_GT(0.6, detectors::kSurveyGateM);
}

TEST(SurveyMatch, NoDetectedLandmarkLeavesEveryEntryUnmatched) {
  const auto m = detectors::matchSurvey({{1.0, 2.0, {}}}, {});
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].id, 0);
}

TEST(SurveyMatch, TheSurveyedRadiusIsTheOneEveryEntryAgreesOn) {
  // within 1 mm
  EXPECT_NEAR(*detectors::surveyedRadius({{0, 0, 0.050}, {1, 0, 0.0505}}), 0.05025, 1e-12);
  // 2 mm apart
  EXPECT_FALSE(detectors::surveyedRadius({{0, 0, 0.050}, {1, 0, 0.052}}).has_value());
  // one not measured
  EXPECT_FALSE(detectors::surveyedRadius({{0, 0, 0.050}, {1, 0, {}}}).has_value());
}

}  // namespace
}  // namespace lidarcal
