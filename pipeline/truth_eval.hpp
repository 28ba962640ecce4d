#pragma once
// Everything that uses the simulator's ground truth: the oracle's (distance, reading) pairs
// and the evaluation of corrected sequences (MSE ratio, seed 000 eq. 31; normalised MSE,
// seed 004 eqs. 31-32). Never used by the calibration itself.

#include <filesystem>
#include <functional>
#include <vector>

#include "calibration/evaluation.hpp"
#include "calibration/filtering.hpp"
#include "calibration/inversion.hpp"
#include "common/calibration_model.hpp"
#include "calibration/range_model_fit.hpp"
#include "common/truth.hpp"
#include "io/sequence.hpp"
#include "io/true_ranges.hpp"

namespace lidarcal::pipeline {

/// Truth of a simulated sequence: truth.json and its true_ranges.csv.
struct SimulationTruth {
  Truth truth;
  std::vector<io::TrueRange> ranges;  ///< every beam of every scan, scan-major
  std::size_t beams = 0;              ///< beams per scan
  const io::TrueRange& at(std::size_t scan, std::size_t beam) const { return ranges.at(scan * beams + beam); }
};
SimulationTruth loadTruth(const std::filesystem::path& truth_json);

/// Odometry scale error of a simulated sequence: similarity scale from the actual to the
/// commanded stop positions.
double commandedScale(const Truth& truth);

/// Oracle pairs: (true distance x scale, raw reading) of every landmark beam with a return.
/// Parts split the scans of each stop in thirds (seed 000 section 4.3).
std::vector<calibration::RangePair> truthPairs(const io::Sequence& raw, const SimulationTruth& truth, double scale);

/// Readings of each landmark beam over the scans of a stop (constant true distance).
std::vector<std::vector<double>> truthBatches(const io::Sequence& raw, const SimulationTruth& truth);

struct Evaluation {
  calibration::RangeComparison landmarks;  ///< beams on landmarks
  calibration::RangeComparison walls;      ///< beams on walls
  calibration::RangeComparison all;        ///< every beam with a return and a truth
  /// Beams whose reading lies beyond the model's fitted range (continued, or kept raw): also
  /// counted in the rows above.
  calibration::RangeComparison beyond;
  std::size_t scans = 0;                   ///< scans compared
  std::size_t lost = 0;                    ///< raw returns that the correction turned into NaN
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
Evaluation evaluate(const io::Sequence& raw, const SimulationTruth& truth, const CorrectedRanges& corrected);
/// Compares raw and corrected scans (matched by file name) with the true ranges; a point is
/// beyond the fitted range where the corrected scan's `correction` field says so.
Evaluation evaluate(const io::Sequence& corrected, const io::Sequence& raw, const SimulationTruth& truth);
/// Compares raw ranges and the model's corrections of them, under `outside` as `correct`
/// applies it, with the true ranges (no files written).
Evaluation evaluate(const CalibrationModel& model, calibration::InversionMethod method, calibration::Outside outside,
                    const io::Sequence& raw, const SimulationTruth& truth);

}  // namespace lidarcal::pipeline
