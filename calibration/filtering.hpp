// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Filtering stage (Alhashimi et al. 2021 section 3.2 phase 3): every point of a scan moved along
// its beam to the corrected distance. Same points, same order; NaN stays NaN; labels and intensity
// kept.

#include <limits>
#include <string>
#include <vector>

#include "calibration/inversion.hpp"
#include "common/calibration_model.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::calibration {

/// What happens to a reading outside the range the model was fitted over.
enum class Outside {
  linear,       ///< corrected by continuing f beyond the edge at its slope there (default)
  keep,         ///< left as it is
  extrapolate,  ///< corrected with the polynomial itself, however it bends out there
  drop,         ///< made a beam without return (NaN)
};
/// The policy of `correct`, `export`, `evaluate` and the live nodes when none is given: a
/// correction that joins the fitted one without a step or a kink, and grows only linearly.
inline constexpr Outside kDefaultOutside = Outside::linear;
const char* toString(Outside o);
/// Parses linear, keep, extrapolate or drop; returns false for anything else.
bool parseOutside(const std::string& name, Outside& out);
/// Every policy's name, default first (for option checks).
std::vector<std::string> outsidePolicies();
/// "linear, keep, extrapolate or drop", for help texts and messages.
std::string outsideNames();

/// The readings a model corrects from its fit: f(d_min)..f(d_max) of its fitted range (every
/// reading when the model does not record one), and what happens to the others. With
/// Outside::linear, a reading y above the window is corrected to
///   d = d_max + (y - f(d_max)) / f'(d_max)
/// (and below it from d_min alike): f continued as its tangent at the edge.
struct CorrectionWindow {
  double reading_min_m = 0.0;         ///< smallest reading corrected by the fit itself, metres
  double reading_max_m = 1e300;       ///< largest reading corrected by the fit itself, metres
  double distance_min_m = 0.0;        ///< d_min: the distance f(d_min) = reading_min_m, metres
  double distance_max_m = 1e300;      ///< d_max: the distance f(d_max) = reading_max_m, metres
  double slope_min = 1.0;             ///< f'(d_min), dimensionless
  double slope_max = 1.0;             ///< f'(d_max), dimensionless
  Outside outside = kDefaultOutside;  ///< what happens to the other readings
};
CorrectionWindow correctionWindow(const CalibrationModel& model, Outside outside);

/// The inverter of a model: distances searched over its fitted range (5 % margin) unless the
/// readings outside are extrapolated with the polynomial, else over inversionWindow(). Throws
/// std::invalid_argument like RangeInverter.
RangeInverter modelInverter(const CalibrationModel& model, InversionMethod method, Outside outside);

/// What happened to one reading.
enum class ReadingFate {
  corrected,        ///< inside the fitted range, moved to the distance the model gives
  extrapolated,     ///< outside the fitted range, moved to the distance the continued model gives
  outside_kept,     ///< outside the correction window, left as it is (Outside::keep)
  outside_dropped,  ///< outside the correction window, made a beam without return (Outside::drop)
  unresolved,       ///< no distance in the inverter's window (a beam without return)
};

/// One reading after correction.
struct CorrectedReading {
  double range_m = 0.0;  ///< corrected distance, metres; NaN for dropped and unresolved readings
  ReadingFate fate = ReadingFate::corrected;  ///< what happened to it
  /// Predictive standard error of the correction, metres: how far the corrected distance's
  /// expectation may lie from the true distance at a distance the fit did not see, the curve's
  /// standard error and the model discrepancy combined, sqrt(curve_standard_error_m^2 +
  /// (sigma_delta / f'(d))^2) (calibration/discrepancy.hpp); the curve's alone when the model
  /// has no discrepancy estimate. Not the reading's own noise. NaN when the model records no
  /// covariance, or for readings left raw, dropped or unresolved.
  double standard_error_m = 0.0;
  /// Standard error of the fitted curve's correction alone (delta method on the coefficients'
  /// covariance), metres; it grows with the distance past the edge for extrapolated readings.
  double curve_standard_error_m = 0.0;
};

/// The two standard errors of a correction at one corrected distance, metres.
struct CorrectionErrors {
  double predictive_m = 0.0;  ///< curve and discrepancy (CorrectedReading::standard_error_m)
  double curve_m = 0.0;  ///< the fitted curve's alone (CorrectedReading::curve_standard_error_m)
};

/// A model ready to correct readings: the single rule behind `correct`, corrected bags, the
/// live nodes and the exported lookup table.
struct ReadingCorrector {
  RangeInverter inverter;          ///< modelInverter(model, method, outside)
  CorrectionWindow window;         ///< correctionWindow(model, outside)
  BiasPolynomial bias;             ///< f, for the continuation beyond the window
  std::vector<double> covariance;  ///< row-major covariance of f's coefficients; empty when unknown
  Discrepancy discrepancy;  ///< the model's discrepancy (none: the curve's standard error alone)
  /// Corrects one positive, finite reading (metres).
  CorrectedReading operator()(double reading_m) const;
  /// The standard errors operator() gives a reading whose corrected distance is distance_m.
  CorrectionErrors errorsAt(double distance_m) const;
};
/// Throws std::invalid_argument like RangeInverter.
ReadingCorrector readingCorrector(const CalibrationModel& model, InversionMethod method,
                                  Outside outside);

/// Counts of what happened to the points of a scan.
struct FilteringStats {
  std::size_t points = 0;     ///< points in the scan
  std::size_t corrected = 0;  ///< returns moved to their corrected distance inside the fitted range
  std::size_t extrapolated = 0;  ///< returns beyond the fitted range moved by the continued model
  std::size_t unresolved = 0;    ///< returns without a root in the window (left as NaN)
  std::size_t outside = 0;       ///< returns beyond the fitted range kept raw or dropped (Outside)
  std::size_t below = 0;         ///< of the returns beyond the fitted range, those below it
  /// Smallest reading below the fitted range and largest above it, metres (+inf and -inf when
  /// none).
  double beyond_min_m = std::numeric_limits<double>::infinity();
  double beyond_max_m = -std::numeric_limits<double>::infinity();
  /// Returns beyond the fitted range, whatever happened to them.
  std::size_t beyond() const { return extrapolated + outside; }
  /// Counts one reading's fate (and its value, when it lies beyond the fitted range: below the
  /// correction window when `below_window`, else above).
  void add(const CorrectedReading& c, double reading_m, bool below_window);
  FilteringStats& operator+=(const FilteringStats& o);
};

/// Returns the corrected scan, with each point's fate (Scan::correction) and standard error
/// (Scan::correction_se). The input is not modified.
io::Scan correctScan(const io::Scan& scan, const ReadingCorrector& correct,
                     FilteringStats* stats = nullptr);

}  // namespace lidarcal::calibration
