// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A simulated sequence's truth as files hold it: truth.json (scene, stops) and the true range of
// every beam (true_ranges.csv beside it).

#include <cstddef>
#include <filesystem>
#include <vector>

#include "common/truth.hpp"
#include "io/true_ranges.hpp"

namespace lidarcal::io {

/// Truth of a simulated sequence: truth.json and its true_ranges.csv.
struct SimulationTruth {
  Truth truth;                    ///< scene, stops (actual and commanded poses), file names
  std::vector<TrueRange> ranges;  ///< every beam of every scan, scan-major
  std::size_t beams = 0;          ///< beams per scan
  /// The true range of `beam` in `scan` (throws std::out_of_range beyond the sequence).
  const TrueRange& at(std::size_t scan, std::size_t beam) const {
    return ranges.at(scan * beams + beam);
  }
};

/// Reads truth.json and the true ranges it names; throws InputError when the ranges are not one
/// row per beam of every scan in (scan, beam) order.
SimulationTruth loadTruth(const std::filesystem::path& truth_json);

}  // namespace lidarcal::io
