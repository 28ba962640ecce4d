// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A fleet of sensors, each calibrated now and then (`lidarcal fleet`): which lidar's bias moved
// since its previous calibration, and which stands out from the rest of the fleet.
//
// Each calibration's bias b(d) = f(d) - d is read at a few distances d_1..d_k, with its
// covariance C = J Sigma_alpha J^T (J_ij = d_i^j, Sigma_alpha the model's alpha_covariance).
//
//   Moved: the change D = b_now - b_before over the distances inside both models' fitted ranges,
//     Wald's statistic W = D^T (C_now + C_before)^+ D (the two calibrations are independent
//     recordings), chi-square with rank(C_now + C_before) degrees of freedom under no change.
//   Outlier: at each distance, the sensor against the other sensors' current calibrations:
//     z = (b - m) / sqrt(tau^2 + se^2 + var(m)), m their median, s = 1.4826 MAD their robust
//     spread, tau^2 = max(0, s^2 - median of their se^2) the spread between sensors beyond
//     what their own estimation noise explains, se the sensor's own standard error and
//     var(m) = (pi / 2) s^2 / n the median's; two-sided p from Student's t with n - 1 degrees
//     of freedom (the scale is estimated from n sensors), Bonferroni over the sensor's distances.
//   False alarms over the fleet: each family of tests (moved, outlier) is adjusted by Holm's
//     step-down method, so the chance of flagging any unchanged sensor is at most `alpha` per
//     family.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "common/calibration_model.hpp"

namespace lidarcal::calibration {

struct FleetConfig {
  /// where the bias is read and compared, metres (> 0, increasing)
  std::vector<double> distances_m = {1.0, 2.0, 3.0};
  /// Family-wise false-alarm rate of each family of tests (moved, outlier), Holm-adjusted. 0.01:
  /// one false alarm in about a hundred weekly fleet checks.
  double alpha = 0.01;
  /// fewest other sensors with the distance in range for a fleet comparison
  std::size_t min_fleet = 5;
  void validate() const;  ///< throws std::invalid_argument
};

/// One calibration of one sensor.
struct FleetEntry {
  std::string sensor;  ///< the sensor's name (unique in the fleet)
  /// when it was calibrated, ISO 8601 (orders a sensor's calibrations; may be empty when it has
  /// one)
  std::string date;
  std::string source;      ///< where the model was read from (for the report)
  CalibrationModel model;  ///< the calibrated model
};

/// The bias at one distance.
struct BiasAt {
  double distance_m = 0.0;  ///< d, metres
  double bias_m = 0.0;      ///< b(d) = f(d) - d, metres
  double se_m = 0.0;        ///< its standard error, metres (NaN without a covariance)
  /// d lies in the model's fitted range (else the bias is an extrapolation and not compared)
  bool inside = false;
  double noise_m = 0.0;  ///< the noise law's standard deviation at d, metres
};

/// One test of a sensor (against its previous calibration or against the fleet).
struct FleetTest {
  bool tested = false;              ///< the test could be made
  std::string why_not;              ///< when not: why (no previous calibration, no covariance, ...)
  std::vector<double> distances_m;  ///< the distances compared
  /// sensor minus reference (previous calibration, or fleet median) at each
  std::vector<double> difference_m;
  std::vector<double> z;   ///< outlier test: each distance's standardised difference
  double statistic = 0.0;  ///< moved: Wald's W; outlier: the largest |z|
  int dof = 0;             ///< moved: degrees of freedom of W; outlier: of the t distribution
  double p = 1.0;        ///< p-value of the sensor's test (outlier: Bonferroni over its distances)
  double p_holm = 1.0;   ///< Holm-adjusted over the family's sensors
  bool flagged = false;  ///< p_holm < alpha
};

/// A sensor's row: its latest calibration and how it compares.
struct FleetRow {
  FleetEntry current;                  ///< the latest calibration
  std::vector<BiasAt> bias;            ///< at each configured distance
  std::optional<FleetEntry> previous;  ///< the calibration before, when there is one
  std::vector<BiasAt> previous_bias;   ///< its bias at each distance (empty when none)
  FleetTest moved;                     ///< against the previous calibration
  FleetTest outlier;                   ///< against the other sensors' current calibrations
};

struct FleetSummary {
  FleetConfig config;          ///< the settings used
  std::vector<FleetRow> rows;  ///< one per sensor, in order of the sensor names
  /// fleet median of the current biases at each distance (NaN: too few sensors)
  std::vector<double> median_bias_m;
  std::vector<double> robust_sd_m;  ///< 1.4826 MAD of them
  /// current calibrations with each distance in their fitted range
  std::vector<std::size_t> sensors_at;
  std::vector<std::string> flagged;  ///< sensors flagged moved or outlier, in row order
};

/// Summarises the calibrations. Throws InputError naming the sources when a sensor has two
/// calibrations of one date, or several calibrations and one without a date.
FleetSummary summarizeFleet(const std::vector<FleetEntry>& entries, const FleetConfig& config);

/// The bias of `model` at each distance, with standard errors from its alpha_covariance.
std::vector<BiasAt> biasAt(const CalibrationModel& model, const std::vector<double>& distances_m);

}  // namespace lidarcal::calibration
