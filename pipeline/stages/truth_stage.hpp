// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The stage `lidarcal run` adds when the sequence has a simulator's truth: the calibrated model
// scored on the corrected scans as written, beside the baselines it is compared with.

#include <filesystem>
#include <vector>

#include "calibration/calibration_config.hpp"
#include "calibration/filtering.hpp"
#include "calibration/inversion.hpp"
#include "io/sequence.hpp"
#include "io/simulation_truth.hpp"
#include "pipeline/reports/report.hpp"
#include "pipeline/stages/stages.hpp"

namespace lidarcal::pipeline {

/// The comparison with the simulator's truth, in the report's order: our model scored on the
/// corrected scans as written (read back from `corrected_dir`, corrected as `how` says), then
/// under the same rule (its method and outside policy) in memory: the closed form (unless ours
/// is one), the oracle in the commanded frame (the odometry scale error no self-calibration
/// sees) and the plain oracle.
std::vector<ComparedModel> compareWithTruth(const io::Sequence& seq,
                                            const std::filesystem::path& corrected_dir,
                                            const io::SimulationTruth& truth,
                                            const SequenceCalibration& cal,
                                            const calibration::CalibrationConfig& config,
                                            const SequenceCorrection& how);

}  // namespace lidarcal::pipeline
