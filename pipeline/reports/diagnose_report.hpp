// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Output of `lidarcal diagnose`: DIR/diagnosis.json (docs/FORMAT.md) and DIR/report.md with
// PNG plots (residuals against each variable, measured next to simulated).

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "diagnosis/diagnosis.hpp"
#include "diagnosis/static_scene.hpp"

namespace lidarcal::pipeline {

/// Where the diagnosed data came from (for the report).
struct DiagnosisSource {
  std::filesystem::path data;  ///< the sequence directory
  std::string sensor;          ///< sensor name, when known
  std::string selection;       ///< e.g. "stop 3 (402 scans)" for static data of a longer sequence
  std::string model;           ///< --model file, when the readings were corrected first
  std::string command;         ///< command line
  /// sequence: readings kept beside the poles (mixed-pixel candidates)
  std::size_t beside_pole_readings = 0;
  std::vector<diagnosis::WallLine> walls;  ///< static: the fitted wall lines
};

/// diagnosis.json content.
nlohmann::ordered_json diagnosisJson(const diagnosis::DiagnosisResult& r,
                                     const DiagnosisSource& src);

/// Writes DIR/diagnosis.json, DIR/report.md and the plots (skipped with a note without gnuplot).
void writeDiagnosis(const std::filesystem::path& dir, const diagnosis::DiagnosisResult& r,
                    const DiagnosisSource& src);

}  // namespace lidarcal::pipeline
