// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Every `lidarcal` subcommand is registered here, in one place. Each lives in its own
// pipeline/cmd_*.cpp: it maps command-line options into the stage config structs, calls
// the stages and prints (the library never prints).

#include <cstdint>
#include <filesystem>
#include <string>

namespace CLI {
class App;
}

namespace lidarcal::pipeline {

void registerCommands(CLI::App& app);

void addSimulateCommand(CLI::App& app);
void addInfoCommand(CLI::App& app);
void addCalibrateCommand(CLI::App& app);
void addCorrectCommand(CLI::App& app);
void addExportCommand(CLI::App& app);
void addEvaluateCommand(CLI::App& app);
void addRunCommand(CLI::App& app);
void addImportCommand(CLI::App& app);
void addDetectCommand(CLI::App& app);
void addPlotCommand(CLI::App& app);
void addNoiseConsistencyCommand(CLI::App& app);
void addLandmarksToObservationsCommand(CLI::App& app);

/// `lidarcal simulate` of a scene with "kind": "observations"
/// (pipeline/commands/cmd_observations.cpp): writes OUT/observations.csv, OUT/odometry.csv,
/// OUT/noise_truth.json.
void simulateObservationScene(const std::string& scene_file, const std::string& out_dir,
                              std::uint64_t seed, bool overwrite);
void addMonteCarloCommand(CLI::App& app);
/// `lidarcal montecarlo-merge` (pipeline/commands/cmd_montecarlo_merge.cpp): shards into the whole
/// study.
void addMonteCarloMergeCommand(CLI::App& app);
void addDiagnoseCommand(CLI::App& app);
/// `lidarcal fleet` (pipeline/commands/cmd_fleet.cpp): many calibrations in one report, moved and
/// outlying sensors flagged.
void addFleetCommand(CLI::App& app);
/// lidarcal watch: the field watcher replayed on a recording (cmd_watch.cpp).
void addWatchCommand(CLI::App& app);
/// `lidarcal odometry` (pipeline/commands/cmd_odometry.cpp): wheel radii, axle and the laser's
/// mounting from odometry tuples (Censi et al. 2013).
void addOdometryCommand(CLI::App& app);
/// `lidarcal odometry-drive` (pipeline/commands/cmd_odometry_drive.cpp): odometry, mounting and
/// range offset in one fit over a drive among poles.
void addOdometryDriveCommand(CLI::App& app);

/// Directory of the bundled data (scenes, example): $LIDARCAL_DATA_DIR, the source tree's
/// data/ for a build tree, or the installed share/lidarcal.
std::filesystem::path dataDir();
/// The bundled example sequence (data/example/scans).
std::filesystem::path bundledExample();

}  // namespace lidarcal::pipeline
