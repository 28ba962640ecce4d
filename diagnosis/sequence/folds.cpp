// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/folds.hpp"

#include <cmath>
#include <map>
#include <set>

#include "common/stats_util.hpp"
#include "diagnosis/dequantise.hpp"

namespace lidarcal::diagnosis::sequence {
namespace {

LandmarkObservations subset(const LandmarkObservations& obs, const std::vector<bool>& keep) {
  LandmarkObservations out;
  out.commanded = obs.commanded;
  out.landmark_radius_m = obs.landmark_radius_m;
  out.range_min_m = obs.range_min_m;
  out.range_max_m = obs.range_max_m;
  for (std::size_t i = 0; i < obs.sightings.size(); ++i)
    if (keep[i]) out.sightings.push_back(obs.sightings[i]);
  return out;
}

}  // namespace

std::optional<std::pair<LandmarkObservations, LandmarkObservations>> foldSplit(
    const LandmarkObservations& obs, const std::vector<int>& fold, int f) {
  std::vector<bool> train(obs.sightings.size()), test(obs.sightings.size());
  bool any = false;
  for (std::size_t i = 0; i < obs.sightings.size(); ++i) {
    train[i] = fold[i] != f;
    test[i] = fold[i] == f;
    any = any || test[i];
  }
  if (!any) return std::nullopt;
  return std::make_pair(subset(obs, train), subset(obs, test));
}

double readingGrid(const LandmarkObservations& obs) {
  std::vector<double> y;
  for (const auto& s : obs.sightings)
    for (const auto& b : s.beams)
      if (std::isfinite(b.range_m)) y.push_back(b.range_m);
  return detectReadingGrid(y);
}

LandmarkObservations dequantised(const LandmarkObservations& obs, double q, std::uint64_t seed) {
  LandmarkObservations out = obs;
  std::vector<double> y;  // the finite readings in sighting and beam order: the order of the draws
  for (const auto& s : out.sightings)
    for (const auto& b : s.beams)
      if (std::isfinite(b.range_m)) y.push_back(b.range_m);
  dequantise(y, q, seed);
  std::size_t k = 0;
  for (auto& s : out.sightings)
    for (auto& b : s.beams)
      if (std::isfinite(b.range_m)) b.range_m = y[k++];
  return out;
}

std::vector<int> foldOfEachSighting(const LandmarkObservations& obs, int k) {
  std::map<std::size_t, std::set<std::size_t>> scans_of_stop;
  for (const auto& s : obs.sightings) scans_of_stop[s.stop].insert(s.scan);
  bool by_scan = true;
  for (const auto& [stop, scans] : scans_of_stop) by_scan = by_scan && scans.size() >= 2;
  std::map<std::size_t, int> position;
  for (const auto& [stop, scans] : scans_of_stop) {
    int i = 0;
    for (std::size_t scan : scans) position[scan] = i++;
  }
  std::vector<int> f(obs.sightings.size());
  for (std::size_t i = 0; i < obs.sightings.size(); ++i) {
    const auto& s = obs.sightings[i];
    f[i] = by_scan ? position[s.scan] % k
                   : static_cast<int>((s.stop + static_cast<std::size_t>(s.landmark)) %
                                      static_cast<std::size_t>(k));
  }
  return f;
}

}  // namespace lidarcal::diagnosis::sequence
