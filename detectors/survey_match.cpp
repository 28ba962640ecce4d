// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/survey_match.hpp"

#include <algorithm>
#include <cmath>

namespace lidarcal::detectors {

std::vector<SurveyMatch> matchSurvey(const std::vector<ReferenceLandmark>& surveyed,
                                     const std::vector<Landmark>& detected) {
  struct Pair {
    double d;
    std::size_t s, l;
  };
  std::vector<Pair> pairs;
  for (std::size_t s = 0; s < surveyed.size(); ++s)
    for (std::size_t l = 0; l < detected.size(); ++l) {
      const double d =
          std::hypot(surveyed[s].x_m - detected[l].x_m, surveyed[s].y_m - detected[l].y_m);
      if (d <= kSurveyGateM) pairs.push_back({d, s, l});
    }
  std::stable_sort(pairs.begin(), pairs.end(),
                   [](const Pair& a, const Pair& b) { return a.d < b.d; });
  std::vector<SurveyMatch> out(surveyed.size());
  std::vector<bool> taken(detected.size(), false);
  for (std::size_t s = 0; s < surveyed.size(); ++s) out[s].entry = s;
  for (const Pair& p : pairs) {
    if (out[p.s].id != 0 || taken[p.l]) continue;
    out[p.s].id = detected[p.l].id;
    out[p.s].distance_m = p.d;
    taken[p.l] = true;
  }
  return out;
}

std::optional<double> surveyedRadius(const std::vector<ReferenceLandmark>& surveyed) {
  std::optional<double> lo, hi;
  for (const auto& l : surveyed) {
    if (!l.radius_m) return std::nullopt;
    lo = std::min(lo.value_or(*l.radius_m), *l.radius_m);
    hi = std::max(hi.value_or(*l.radius_m), *l.radius_m);
  }
  if (!lo || *hi - *lo > 1e-3) return std::nullopt;
  return 0.5 * (*lo + *hi);
}

}  // namespace lidarcal::detectors
