#pragma once
// Filtering stage (seed 000 section 3.2 phase 3): every point of a scan moved along its beam
// to the corrected distance. Same points, same order; NaN stays NaN; labels and intensity kept.

#include <string>

#include "calibration/inversion.hpp"
#include "common/calibration_model.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::calibration {

struct FilteringStats {
  std::size_t points = 0;       ///< points in the scan
  std::size_t corrected = 0;    ///< returns moved to their corrected distance
  std::size_t unresolved = 0;   ///< returns without a root in the window (left as NaN)
  std::size_t outside = 0;      ///< returns outside the fitted reading range (kept or dropped, see Outside)
};

/// What happens to a reading outside the range the model was fitted over.
enum class Outside {
  keep,         ///< left as it is (default: the model says nothing there)
  extrapolate,  ///< corrected with the polynomial all the same
  drop,         ///< made a beam without return (NaN)
};
/// The policy of `correct`, `export`, `evaluate` and the live nodes when none is given.
inline constexpr Outside kDefaultOutside = Outside::keep;
const char* toString(Outside o);
/// Parses keep, extrapolate or drop; returns false for anything else.
bool parseOutside(const std::string& name, Outside& out);

/// The readings a model corrects: f(d_min)..f(d_max) of its fitted range (every reading when the
/// model does not record one), and the policy for the others.
struct CorrectionWindow {
  double reading_min_m = 0.0;                  ///< smallest reading corrected, metres
  double reading_max_m = 1e300;                ///< largest reading corrected, metres
  Outside outside = kDefaultOutside;           ///< what happens to the others
};
CorrectionWindow correctionWindow(const CalibrationModel& model, Outside outside);

/// The inverter of a model: distances searched over its fitted range (5 % margin) unless the
/// readings outside are extrapolated, else over inversionWindow(). Throws std::invalid_argument
/// like RangeInverter.
RangeInverter modelInverter(const CalibrationModel& model, InversionMethod method, Outside outside);

/// What happened to one reading.
enum class ReadingFate {
  corrected,        ///< moved to the distance the model gives
  outside_kept,     ///< outside the correction window, left as it is (Outside::keep)
  outside_dropped,  ///< outside the correction window, made a beam without return (Outside::drop)
  unresolved,       ///< no distance in the inverter's window (a beam without return)
};

/// One reading after correction.
struct CorrectedReading {
  double range_m = 0.0;                     ///< corrected distance, metres; NaN for dropped and unresolved readings
  ReadingFate fate = ReadingFate::corrected;  ///< what happened to it
};

/// Corrects one positive, finite reading (metres): the single rule behind `correct`, corrected
/// bags, the ROS node and the exported lookup table.
CorrectedReading correctReading(double reading_m, const RangeInverter& inverter, const CorrectionWindow& window);

/// A model ready to correct readings: its inverter and its window.
struct ReadingCorrector {
  RangeInverter inverter;   ///< modelInverter(model, method, outside)
  CorrectionWindow window;  ///< correctionWindow(model, outside)
  CorrectedReading operator()(double reading_m) const { return correctReading(reading_m, inverter, window); }
};
/// Throws std::invalid_argument like RangeInverter.
ReadingCorrector readingCorrector(const CalibrationModel& model, InversionMethod method, Outside outside);

/// Returns the corrected scan. The input is not modified.
io::Scan correctScan(const io::Scan& scan, const RangeInverter& inverter, FilteringStats* stats = nullptr,
                     const CorrectionWindow& window = {});

}  // namespace lidarcal::calibration
