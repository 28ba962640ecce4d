// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A summary of a scan sequence: what a user checks before calibrating.

#include <cstddef>
#include <functional>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "io/sequence.hpp"

namespace lidarcal::pipeline {

struct SequenceSummary {
  std::size_t scans = 0;  ///< .pcd files
  std::size_t stops = 0;  ///< groups of scans with the same VIEWPOINT
  std::size_t min_scans_per_stop = 0, max_scans_per_stop = 0;
  std::size_t min_beams = 0, max_beams = 0;                         ///< points per scan
  std::size_t points = 0;                                           ///< all points
  std::size_t returns = 0;                                          ///< points that are not NaN
  double min_range_m = 0.0, max_range_m = 0.0, mean_range_m = 0.0;  ///< over returns
  double path_length_m = 0.0;                 ///< sum of distances between consecutive stops
  double max_step_m = 0.0, min_step_m = 0.0;  ///< distances between consecutive stops
};

/// Reads every scan once (streaming) and summarises. `on_scan` is called after each scan.
SequenceSummary summarize(const io::Sequence& seq,
                          const std::function<void(std::size_t)>& on_scan = {});

/// Human-readable summary (Markdown).
std::string toMarkdown(const io::Sequence& seq, const SequenceSummary& s);

/// The same for scripts (`lidarcal info --json`): every field of the summary under its name
/// with its unit, and the sequence.json items that are set (docs/FORMAT.md).
nlohmann::ordered_json toJson(const io::Sequence& seq, const SequenceSummary& s);

}  // namespace lidarcal::pipeline
