// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What `lidarcal fleet` writes (docs/FORMAT.md, "Fleet report"): fleet.json for machines,
// fleet.md and the bias curves of every sensor in one plot for people. Text only; the command
// writes the files and runs gnuplot.

#include <string>

#include <nlohmann/json.hpp>

#include "calibration/fleet.hpp"

namespace lidarcal::pipeline {

/// fleet.json: settings, the fleet's median bias per distance, one object per sensor with its
/// bias, noise, status, warnings and both tests, and the flagged sensors. NaN is null.
nlohmann::json fleetJson(const calibration::FleetSummary& summary);

/// fleet.md: what was flagged and why, a table of one row per sensor, how the tests work, and
/// the plot `plot_file` (left out when empty: gnuplot missing).
std::string fleetMarkdown(const calibration::FleetSummary& summary, const std::string& plot_file);

/// gnuplot script drawing every sensor's current bias curve over its fitted range into
/// `plot_file` (SVG): unflagged sensors grey, flagged ones in colour with their previous
/// calibration dashed, and the fleet median with its robust spread at the distances. Data inline.
std::string fleetGnuplot(const calibration::FleetSummary& summary, const std::string& plot_file);

}  // namespace lidarcal::pipeline
