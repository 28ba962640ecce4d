#pragma once
// The truth evaluation under the names the commands have used: files in io/simulation_truth.hpp,
// scoring in calibration/truth_evaluation.hpp (new code includes those).

#include "calibration/truth_evaluation.hpp"
#include "io/simulation_truth.hpp"

namespace lidarcal::pipeline {

using calibration::calibrateOracle;
using calibration::commandedScale;
using calibration::CorrectedRanges;
using calibration::CorrectedScanRanges;
using calibration::evaluate;
using calibration::Evaluation;
using calibration::truthBatches;
using calibration::truthPairs;
using io::loadTruth;
using io::SimulationTruth;

}  // namespace lidarcal::pipeline
