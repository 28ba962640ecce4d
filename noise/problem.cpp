// SPDX-License-Identifier: BSD-3-Clause
#include "noise/problem.hpp"

#include <algorithm>
#include <map>
#include <string>

#include "common/errors.hpp"

namespace lidarcal::noise {

NoiseProblem makeNoiseProblem(const std::vector<Observation>& observations,
                              const std::vector<OdometryStep>& odometry) {
  NoiseProblem p;
  p.stops = static_cast<int>(odometry.size());
  p.odometry = odometry;
  if (p.stops == 0)
    throw InputError("odometry", "", "holds no stop",
                     "odometry.csv must list at least stop 0 (the start)");
  for (std::size_t k = 0; k < odometry.size(); ++k)
    if (odometry[k].stop != static_cast<int>(k))
      throw InputError("odometry", "row " + std::to_string(k),
                       "stops must be 0, 1, 2, ... in order", "see docs/FORMAT.md");

  std::map<int, int> dense;
  for (const auto& o : observations) {
    if (o.stop < 0 || o.stop >= p.stops)
      throw InputError(
          "observations", "stop " + std::to_string(o.stop),
          "is not in the odometry (which lists stops 0.." + std::to_string(p.stops - 1) + ")",
          "observations.csv and odometry.csv must come from the same run");
    if (o.sensor < 0)
      throw InputError("observations", "sensor " + std::to_string(o.sensor), "must be >= 0");
    if (o.landmark < 0) {
      ++p.skipped_unassociated;
      continue;
    }
    Observation copy = o;
    auto it = dense.find(o.landmark);
    if (it == dense.end()) {
      it = dense.emplace(o.landmark, static_cast<int>(p.landmark_ids.size())).first;
      p.landmark_ids.push_back(o.landmark);
    }
    copy.landmark = it->second;
    p.sensors = std::max(p.sensors, o.sensor + 1);
    p.observations.push_back(copy);
  }
  if (p.observations.empty())
    throw DataError("observations", "",
                    "no observation with a known landmark (all are -1 or the file is empty)",
                    "associate the detections with landmarks first (landmark ids >= 0)");
  p.landmarks = static_cast<int>(p.landmark_ids.size());
  std::stable_sort(p.observations.begin(), p.observations.end(),
                   [](const Observation& a, const Observation& b) { return a.stop < b.stop; });
  p.per_sensor.assign(static_cast<std::size_t>(p.sensors), 0);
  for (const auto& o : p.observations) ++p.per_sensor[static_cast<std::size_t>(o.sensor)];
  for (int s = 0; s < p.sensors; ++s)
    if (p.per_sensor[static_cast<std::size_t>(s)] == 0)
      throw DataError("observations", "sensor " + std::to_string(s),
                      "has no associated observation",
                      "sensor ids must be 0..S-1 without gaps, each with observations");
  p.stop_begin.assign(static_cast<std::size_t>(p.stops) + 1, 0);
  for (const auto& o : p.observations) ++p.stop_begin[static_cast<std::size_t>(o.stop) + 1];
  for (std::size_t k = 1; k < p.stop_begin.size(); ++k) p.stop_begin[k] += p.stop_begin[k - 1];
  return p;
}

}  // namespace lidarcal::noise
