// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The report's plots (pipeline/reports/report.hpp): the data files, the gnuplot script and the
// pictures. Internal to the reports.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/reports/report.hpp"

namespace lidarcal::pipeline {

struct PlotData {
  std::string distance, curve, noise, raw, corrected, circles, stops, histogram, truth;
  std::size_t readings = 0;  ///< rows of `distance`
  FittedRange fitted;
};

/// The plot data of a calibration on landmarks: the readings against their estimated (or, with
/// `truth`, true) distance, the noise per bin, the map's circles, stops and points.
PlotData plotData(const LandmarkObservations& obs, const CalibrationModel& m,
                  const std::vector<Cylinder>& truth);

/// The plots of a calibration against reference measurements: the readings whose true distance
/// the reference gives (or, for a span's walls, the fit places), and on the map one scan per stop
/// of them, raw and corrected, at the commanded poses.
PlotData knownPlotData(const std::vector<calibration::KnownReading>& known,
                       const LandmarkObservations& obs, const CalibrationModel& m);

/// Writes the plot data and plots.gp into `dir`, draws them, and adds the Plots section to `md`
/// (or why there are none).
void writePlotsSection(std::ostringstream& md, const std::filesystem::path& dir,
                       const CalibrationModel& m, const std::optional<PlotData>& p,
                       const FittedRange& fitted);

}  // namespace lidarcal::pipeline
