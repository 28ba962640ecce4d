// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Scoring against a simulator's truth (never used by the calibration itself): the oracle's
// (distance, reading) pairs and its model, and how much closer corrected ranges are to the
// true ones than raw ones (MSE ratio, Alhashimi et al. 2021 eq. 31; normalised MSE, Alhashimi
// et al. 2016 eqs. 31-32). The scans are read one at a time.

#include <functional>
#include <vector>

#include "calibration/calibration_config.hpp"
#include "calibration/evaluation.hpp"
#include "calibration/filtering.hpp"
#include "calibration/inversion.hpp"
#include "calibration/range_model_fit.hpp"
#include "common/calibration_model.hpp"
#include "common/truth.hpp"
#include "io/sequence.hpp"
#include "io/simulation_truth.hpp"

namespace lidarcal::calibration {

/// Odometry scale error of a simulated sequence: similarity scale from the actual to the
/// commanded stop positions (1 with fewer than two stops).
double commandedScale(const Truth& truth);

/// Oracle pairs: (true distance x scale, raw reading) of every landmark beam with a return.
/// Parts split the scans of each stop in thirds (Alhashimi et al. 2021 section 4.3). Throws
/// InputError when `truth` does not describe `raw`.
std::vector<RangePair> truthPairs(const io::Sequence& raw, const io::SimulationTruth& truth,
                                  double scale);

/// Readings of each landmark beam over the scans of a stop (constant true distance).
std::vector<std::vector<double>> truthBatches(const io::Sequence& raw,
                                              const io::SimulationTruth& truth);

/// The oracle of Alhashimi et al. 2016 on a simulated sequence: the range model fitted against the
/// true distances of the landmark beams (calibrateAgainstTruth), scaled by `scale` (1: plain
/// oracle, method "oracle", the actual stop poses; commandedScale(): the best any
/// self-calibration can do, in the commanded frame, method "oracle-commanded"), with the true
/// landmarks.
CalibrationModel calibrateOracle(const io::Sequence& raw, const io::SimulationTruth& truth,
                                 double scale, const CalibrationConfig& config);

struct Evaluation {
  RangeComparison landmarks;  ///< beams on landmarks
  RangeComparison walls;      ///< beams on walls
  RangeComparison all;        ///< every beam with a return and a truth
  /// Beams whose reading lies beyond the model's fitted range (continued, or kept raw): also
  /// counted in the rows above.
  RangeComparison beyond;
  std::size_t scans = 0;  ///< scans compared
  std::size_t lost = 0;   ///< raw returns that the correction turned into NaN
};

/// The corrected scan of one raw scan: a range per point (NaN where there is none) and whether
/// its reading lay beyond the model's fitted range.
struct CorrectedScanRanges {
  std::vector<double> range_m;  ///< corrected range per point, metres
  std::vector<bool> beyond;     ///< per point: beyond the fitted range (empty: none is)
};
/// Corrected ranges of raw scan `index`.
using CorrectedRanges = std::function<CorrectedScanRanges(std::size_t index, const io::Scan& raw)>;

/// Compares raw ranges and their corrections with the true ranges.
Evaluation evaluate(const io::Sequence& raw, const io::SimulationTruth& truth,
                    const CorrectedRanges& corrected);
/// Compares raw and corrected scans (matched by file name) with the true ranges; a point is
/// beyond the fitted range where the corrected scan's `correction` field says so.
Evaluation evaluate(const io::Sequence& corrected, const io::Sequence& raw,
                    const io::SimulationTruth& truth);
/// Compares raw ranges and the model's corrections of them, under `outside` as `correct`
/// applies it, with the true ranges (no files written).
Evaluation evaluate(const CalibrationModel& model, InversionMethod method, Outside outside,
                    const io::Sequence& raw, const io::SimulationTruth& truth);

}  // namespace lidarcal::calibration
