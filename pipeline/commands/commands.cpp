// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/commands/commands.hpp"

#include <cstdlib>

#include <CLI/CLI.hpp>

namespace lidarcal::pipeline {

void registerCommands(CLI::App& app) {
  addSimulateCommand(app);
  addInfoCommand(app);
  addRunCommand(app);
  addCalibrateCommand(app);
  addCorrectCommand(app);
  addExportCommand(app);
  addEvaluateCommand(app);
  addImportCommand(app);
  addDetectCommand(app);
  addPlotCommand(app);
  addNoiseConsistencyCommand(app);
  addLandmarksToObservationsCommand(app);
  addMonteCarloCommand(app);
  addMonteCarloMergeCommand(app);
  addDiagnoseCommand(app);
  addFleetCommand(app);
  addWatchCommand(app);
  addOdometryCommand(app);
  addOdometryDriveCommand(app);
}

std::filesystem::path dataDir() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("LIDARCAL_DATA_DIR"); env && *env) return env;
  std::error_code ec;
  if (fs::is_directory(LIDARCAL_SOURCE_DATA_DIR, ec)) return LIDARCAL_SOURCE_DATA_DIR;
  return LIDARCAL_INSTALL_DATA_DIR;
}

std::filesystem::path bundledExample() { return dataDir() / "example" / "scans"; }

}  // namespace lidarcal::pipeline
