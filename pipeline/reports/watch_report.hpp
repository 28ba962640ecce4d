// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What `lidarcal watch` writes and prints: the timeline of checks and refits (timeline.json,
// docs/FORMAT.md), the plot of the shift over the drive (timeline.png) and the lines a user reads
// (one per alarm and switch, then a summary).

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "watch/events.hpp"
#include "watch/range_change.hpp"
#include "watch/watch_settings.hpp"

namespace lidarcal::pipeline {

/// A refit as the timeline keeps it: the candidate's summary, the decision, and the model file
/// written when it was adopted.
struct RefitRecord {
  watch::RefitEvent event;  ///< the candidate is kept only when adopted
  std::string model_file;   ///< models/model_vN.json when adopted (relative to the output)
};

/// Everything the timeline holds.
struct WatchTimeline {
  std::string input;                           ///< the recording replayed
  std::string model_file;                      ///< the model given ("" in learn mode without one)
  watch::WatchSettings settings;               ///< as run
  std::optional<watch::RangeChange> injected;  ///< --inject
  std::vector<watch::CheckEvent> checks;       ///< every check, in order
  std::vector<RefitRecord> refits;             ///< every refit, in order
  watch::WatchState final_state;               ///< the state at the end
};

/// timeline.json (format lidarcal-watch/1).
nlohmann::ordered_json timelineJson(const WatchTimeline& t);

/// The gnuplot data and script of the plot (timeline.dat, timeline.gp) into `dir`; the number of
/// checks drawn. With none (no test was made) it writes nothing: there is no plot to draw.
std::size_t writeTimelinePlot(const std::filesystem::path& dir, const WatchTimeline& t);

/// The line printed for an alarm, a rejected model or a switch (empty for a quiet check).
std::string checkLine(const watch::CheckEvent& e);
std::string refitLine(const watch::RefitEvent& e);

/// The closing summary for stdout.
std::string watchSummary(const WatchTimeline& t);

}  // namespace lidarcal::pipeline
