// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Joint calibration of several 2D lidars on one vehicle against fixed poles in unknown places:
// the single-sensor joint refinement of Alhashimi et al. 2021 (section 3.3, every pose, pole and
// the bias in one maximum-likelihood fit) written with one block of parameters per sensor. A
// beam at angle a of sensor s, in a scan taken at the vehicle's stop k, on pole p, reads
//     y = f_s(d) + e,   d = distance along the ray from T_k M_s at direction psi_k + yaw_s + flip_s
//     a
// to the circle (c_p, r), f_s the sensor's bias polynomial (Alhashimi et al. 2021 eq. 3), T_k the
// vehicle's pose, M_s = (x_s, y_s, yaw_s) the sensor's mounting on the vehicle. The readings of
// one beam on one pole at one stop are pooled into their mean, whose variance is
//     sigma_s(d)^2 / n + tau_s^2,
// sigma_s the sensor's noise law (constant or Alhashimi et al. 2016 eq. 1's sigma_e f(d)^2, chosen
// per sensor by likelihood) and tau_s the part of a beam's error that repeats from scan to scan
// (a real sensor's systematic error on one surface; 0 for independent noise). The vehicle's
// poses enter with a prior around the recorded ones (stop and go, Alhashimi et al. 2021 eq. 8)
// or, for a vehicle that never stops, as odometry steps (motion prior).
//
// Gauge and identifiability (docs/FORMAT.md, "Several sensors"):
//  - vehicle frame: with the vehicle's poses recorded and a turn between the stops, every
//    mounting is found in the vehicle frame (a mounting's position shows only through the
//    turns; with straight motion only, it trades off against the poles' positions);
//  - relative frame: otherwise (static vehicle, poses unknown, no turn) the reference sensor's
//    mounting is held at its prior and the others are found relative to it; only the relative
//    mountings mean anything;
//  - range scale: without a distance the vehicle travelled (recorded poses over at least
//    min_travel_m), a scale common to every sensor's readings and to the geometry is free: the
//    reference sensor's alpha_1 is held at its start (1) and the others' scales are relative to it.

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calibration/joint_refinement.hpp"
#include "common/range_model.hpp"
#include "common/rig.hpp"
#include "common/status.hpp"

namespace lidarcal::calibration {

/// The frame the mountings are estimated in.
enum class RigFrame {
  automatic,  ///< vehicle when the recorded poses allow it (known, a turn), else relative (default)
  vehicle,    ///< every mounting in the vehicle frame (needs recorded poses and a turn)
  relative,   ///< the reference sensor held at its prior; the others relative to it
};
const char* toString(RigFrame f);

struct RigConfig {
  RigFrame frame = RigFrame::automatic;  ///< see RigFrame. Default automatic
  /// reference sensor (relative frame; the range scale's gauge). Default 0
  std::size_t reference = 0;
  /// stop and go: prior std. dev. of each coordinate of a stop around its recorded pose, metres.
  /// Default 0.02
  double sigma_vehicle_m = 0.02;
  /// stop and go: the same for its heading, radians. Default 0.0087 (0.5 deg)
  double sigma_vehicle_rad = 0.0087;
  /// odometry steps between consecutive stops (continuous motion). Default automatic
  MotionPrior motion = MotionPrior::automatic;
  /// automatic: a vehicle that never stops has at least this many stops, most of one scan. Default
  /// 20
  int motion_min_stops = 20;
  /// motion prior: std. dev. of each step coordinate per metre of step. Default 0.1
  double motion_sigma_fraction = 0.1;
  double motion_sigma_floor_m = 0.002;  ///< plus this, metres. Default 0.002
  /// of the heading change per metre of step, rad/m. Default 0.1
  double motion_heading_sigma_rad_per_m = 0.1;
  double motion_heading_floor_rad = 0.002;  ///< plus this, radians. Default 0.002
  /// Bias order per sensor; empty: chosen per sensor by BIC among 1..max_order. Default empty.
  std::vector<int> orders;
  int max_order = 2;  ///< highest order tried when choosing. Default 2
  /// Noise laws tried per sensor (the most likely is kept): constant and squared by default.
  std::vector<NoiseKind> noise_kinds{NoiseKind::constant, NoiseKind::squared};
  /// beams passing within this fraction of the radius from a pole's centre are used. Default 0.7
  double lateral_fraction = 0.7;
  int outer_iterations = 8;         ///< noise re-estimations at most. Default 8
  int max_solver_iterations = 100;  ///< Ceres iterations per solve. Default 100
  /// vehicle frame: the recorded headings must span this much, radians. Default 0.35 (20 deg)
  double min_turn_rad = 0.35;
  /// the recorded poses give the range scale when they span this much, metres. Default 0.5
  double min_travel_m = 0.5;
  /// A mounting whose standard error exceeds these is not identifiable (exit 3 with the reason).
  double max_mounting_se_m = 0.25;    ///< metres. Default 0.25
  double max_mounting_se_rad = 0.17;  ///< radians. Default 0.17 (10 deg)
  /// A range model whose correction at the middle of its fitted distances has a larger standard
  /// error is reported as not determined (its block is written with that status; `correct`
  /// refuses it). Metres. Default 0.01.
  double max_model_se_m = 0.01;
  /// Sensors whose prior is not known (RigSensor::prior_known false): fit both flips and keep the
  /// more likely. Default true.
  bool estimate_unknown_flips = true;
  void validate(std::size_t sensors) const;  ///< throws std::invalid_argument
};

/// One sensor as calibrated.
struct RigSensorEstimate {
  Mounting mounting;  ///< in the vehicle frame (relative frame: the reference at its prior)
  /// of (x, y, yaw); zero when held
  Eigen::Matrix3d mounting_covariance = Eigen::Matrix3d::Zero();
  bool mounting_held = false;        ///< the reference of the relative frame
  RangeModel model;                  ///< bias f_s and noise law sigma_s
  Eigen::MatrixXd alpha_covariance;  ///< of alpha_0..alpha_n
  bool scale_held = false;           ///< alpha_1 held at its start (the range scale's gauge)
  /// tau_s: std. dev. of a beam's error that repeats from scan to scan, metres
  double beam_scatter_m = 0.0;
  /// orders tried and the whole fit's BIC with each
  std::vector<std::pair<int, double>> order_bic;
  /// flip estimated: log-likelihood of the kept flip over the other (0: not estimated)
  double flip_log_likelihood_ratio = 0.0;
  std::size_t readings = 0;             ///< readings used
  std::size_t residuals = 0;            ///< pooled residuals (beam means)
  double residual_rms_m = 0.0;          ///< RMS of the beam means minus f(d)
  double d_min_m = 0.0, d_max_m = 0.0;  ///< true distances the fit covers, metres
  std::size_t poles = 0;                ///< poles it saw
  std::size_t shared_poles = 0;         ///< of them, poles another sensor saw too
  /// Standard error of f_s at the middle of the fitted distances (delta method), metres.
  double model_se_m = 0.0;
  /// ok, or why this sensor's range model is not determined (not_identifiable): its block is
  /// written with that status and `correct` refuses it; the mountings may still stand.
  Status model_status;
};

/// A pole as calibrated.
struct RigPoleEstimate {
  int id = 0;                   ///< pole id
  double x_m = 0.0, y_m = 0.0;  ///< centre in the frame of the vehicle's poses, metres
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  ///< m^2
  std::vector<std::size_t> sensors;                      ///< sensors that saw it
};

/// Sensor `sensor` seen from sensor `reference`: where it sits in the reference's frame.
struct RigRelativeMounting {
  std::size_t reference = 0, sensor = 0;  ///< indices into the sensors
  Pose2 pose;                             ///< x, y, yaw of `sensor` in `reference`'s frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  ///< of (x, y, yaw)
};

struct RigResult {
  /// ok, or why the data cannot give the mountings (not_identifiable, no_shared_landmark,
  /// too_few_readings, solver_failed), with what to record instead.
  Status status{StatusCode::not_run, ""};
  bool ok() const { return status.ok(); }
  RigFrame frame = RigFrame::relative;        ///< vehicle or relative (never automatic)
  std::size_t reference = 0;                  ///< reference sensor
  std::vector<RigSensorEstimate> sensors;     ///< one per sensor, in the input's order
  std::vector<RigPoleEstimate> poles;         ///< by id
  std::vector<Pose2> vehicle;                 ///< refined pose of each stop
  double radius_m = 0.0;                      ///< pole radius (given or estimated)
  double radius_se_m = 0.0;                   ///< its standard error (0 when given)
  std::vector<RigRelativeMounting> relative;  ///< every other sensor relative to the reference
  bool motion_prior = false;                  ///< odometry steps were the vehicle's prior
  bool scale_free = false;  ///< the common range scale was a gauge (reference alpha_1 held)
  /// What the data determine and what they cannot, in words (gauge, scale, flips).
  std::vector<std::string> notes;
  int solver_iterations = 0;        ///< Ceres iterations, every solve of the kept fit
  double neg_log_likelihood = 0.0;  ///< of the pooled readings at the solution, nats
  double bic = 0.0;                 ///< k ln N + 2 NLL over the pooled readings
  std::size_t parameters = 0;       ///< free parameters of the kept fit
};

/// Calibrates every sensor of the rig together. Throws std::invalid_argument for an invalid
/// config; data that cannot give the mountings come back as a status.
RigResult calibrateRig(const RigObservations& obs, const RigConfig& config);

/// Sets e.model_se_m (the standard error of f at the middle of the fitted distances) and marks
/// the range model not determined (e.model_status not_identifiable, with what to record) when
/// that exceeds config.max_model_se_m, or when the model changes readings by more than lidars
/// are built to (calibration/plausibility.hpp, kImplausibleCorrection) anywhere in
/// [e.d_min_m, e.d_max_m]: over a short span of distances a polynomial trades off against the
/// mounting, and a small standard error then does not make the model right. `name` names the
/// sensor in the message.
void checkRangeModel(RigSensorEstimate& e, const std::string& name, const RigConfig& config);

/// The relative mounting of `sensor` in `reference`'s frame with its covariance, from both
/// mountings and their joint covariance (6 x 6: reference x, y, yaw, then sensor's).
RigRelativeMounting relativeMountingWithCovariance(const Mounting& reference,
                                                   const Mounting& sensor,
                                                   const Eigen::Matrix<double, 6, 6>& covariance);

}  // namespace lidarcal::calibration
