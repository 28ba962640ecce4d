// SPDX-License-Identifier: BSD-3-Clause
#include "io/simulation_truth.hpp"

#include <string>

#include "common/errors.hpp"
#include "io/scene_io.hpp"

namespace lidarcal::io {

SimulationTruth loadTruth(const std::filesystem::path& truth_json) {
  SimulationTruth t;
  t.truth = readTruth(truth_json);
  const auto csv = truth_json.parent_path() / t.truth.true_ranges_file;
  t.ranges = readTrueRanges(csv);
  t.beams = static_cast<std::size_t>(t.truth.scene.sensor.beams);
  std::size_t scans = 0;
  for (const auto& s : t.truth.stops) scans += s.scans;
  if (t.ranges.size() != scans * t.beams)
    throw InputError(csv.string(), "",
                     "holds " + std::to_string(t.ranges.size()) + " rows, truth.json promises " +
                         std::to_string(scans * t.beams),
                     "regenerate the simulation");
  for (std::size_t i = 0; i < t.ranges.size(); ++i)
    if (t.ranges[i].scan != i / t.beams || t.ranges[i].beam != i % t.beams)
      throw InputError(csv.string(), "line " + std::to_string(i + 2),
                       "rows are not in scan, beam order", "regenerate the simulation");
  return t;
}

}  // namespace lidarcal::io
