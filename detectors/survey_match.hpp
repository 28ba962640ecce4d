// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Surveyed landmarks (REF.json `landmarks`, common/reference.hpp) matched to the landmarks the
// detection found: the closest pairs first, one to one, within a gate.

#include <cstddef>
#include <optional>
#include <vector>

#include "common/reference.hpp"
#include "detectors/association.hpp"

namespace lidarcal::detectors {

/// A surveyed landmark (REF.json `landmarks[entry]`) and the detected landmark it stands for.
struct SurveyMatch {
  std::size_t entry = 0;  ///< index in REF.json's landmarks
  int id = 0;             ///< detected landmark id (0: none within the gate)
  /// from the surveyed centre to the detected landmark's position, metres
  double distance_m = 0.0;
};

/// Farthest a surveyed centre may lie from the detected landmark it is matched to, metres (the
/// detected positions come from the commanded poses and a raw, biased range: decimetres off are
/// common).
inline constexpr double kSurveyGateM = 0.5;

/// One match per surveyed centre, in their order: the closest (surveyed, detected) pairs first,
/// one to one, within kSurveyGateM; an entry without one gets id 0.
std::vector<SurveyMatch> matchSurvey(const std::vector<ReferenceLandmark>& surveyed,
                                     const std::vector<Landmark>& detected);

/// The radius the surveyed landmarks agree on (within 1 mm; their mean), metres, if every one gives
/// it.
std::optional<double> surveyedRadius(const std::vector<ReferenceLandmark>& surveyed);

}  // namespace lidarcal::detectors
