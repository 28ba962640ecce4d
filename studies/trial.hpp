#pragma once
// One Monte Carlo trial of the seed 000 study (sections 4.1-4.2): simulate a calibration run
// over a landmark layout, calibrate it with the paper's closed form (triangulation + LS + AIC),
// our joint refinement and the oracle (the same LS + AIC against the true distances), and score
// each on a fresh draw of the same layout with the MSE ratio (eq. 31). The landmark positions
// of the triangulation (section 3.1) and of the joint refinement are scored against the truth.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "calibration/calibrate.hpp"
#include "common/scene.hpp"
#include "studies/placement.hpp"

namespace lidarcal::studies {

/// How the scans are produced.
enum class Level {
  landmark,  ///< seed 000 eqs. 3, 5, 8 per landmark, beams ray-cast on each landmark (fast)
  scan,      ///< whole scans ray-cast, landmarks found by the detector (detection in the loop)
};
const char* toString(Level level);
bool parseLevel(const std::string& name, Level& level);

/// What the angular noise sigma_theta of a cell perturbs.
enum class AngleNoise {
  bearing,  ///< eq. 5: each landmark's centre bearing at each stop, independently (the paper's model)
  heading,  ///< the robot's heading at each stop: shared by every landmark and beam of the stop
};
const char* toString(AngleNoise noise);
bool parseAngleNoise(const std::string& name, AngleNoise& noise);

/// One point of a study grid.
struct Cell {
  int landmarks = 5;                           ///< number of landmarks L
  double sigma_s_m = 0.01;                     ///< std. dev. of each stop coordinate (eq. 8), metres
  double sigma_theta_rad = 0.03490658503988659;  ///< std. dev. of the angle noise (eq. 5), radians (2 degrees)
};

/// The three estimators, in output order.
enum class Estimator { closed_form = 0, joint = 1, oracle = 2 };
constexpr std::size_t kEstimators = 3;
const char* toString(Estimator e);

struct TrialConfig {
  Level level = Level::landmark;               ///< simulation level
  /// Angle-noise model. The landmark level defaults to the paper's (bearing); the scan level
  /// supports heading only (the detector's bearings carry their own noise).
  AngleNoise angle_noise = AngleNoise::bearing;
  PathSpec path = defaultPath();               ///< stops (20), step (0.15 m), scans per stop (10); sigmas from the cell
  RangeModel sensor = paperSensor();           ///< seed 000 section 4.1: n = 2, alpha, beta = 0.05 alpha; window 0.2-6 m
  /// Multiplies the noise coefficients beta of `sensor` (1: the paper's 5 % of the range). The
  /// detector cannot find 12 cm poles through that much noise beyond about a metre, so scan-level
  /// studies run with less (the command's default there is 0.2).
  double noise_scale = 1.0;
  PlacementConfig placement;                   ///< random layouts
  int max_order = 3;                           ///< n_max of the order selection (all estimators)
  int joint_outer_iterations = 3;              ///< noise re-estimations of the joint refinement (library default 6)
  bool joint_average_scans = true;             ///< joint refinement on per-stop beam averages (averageScans)
  int scan_beams = 360;                        ///< scan level: beams per sweep (1 degree apart)
  double min_sigma_s_m = 0.001;                ///< floor of the sigma_s the estimators are told, metres
  double min_sigma_theta_rad = 0.0017453292519943296;  ///< floor of the sigma_theta they are told (0.1 degree)
  void validate() const;                       ///< throws std::invalid_argument

  static PathSpec defaultPath();
  static RangeModel paperSensor();
};

/// Position error of one landmark, in a frame attached to it: radial along the line from the
/// middle of the commanded path to the true centre (positive: estimated farther away), tangential
/// across it (positive: counter-clockwise).
struct PositionError {
  double radial_m = 0.0;      ///< metres
  double tangential_m = 0.0;  ///< metres
};

struct EstimatorOutcome {
  bool ran = false;                ///< the estimator was run in this trial
  bool ok = false;                 ///< it produced a model (status ok)
  double mse_ratio = 0.0;          ///< eq. 31 on the test draw's readings averaged per stop and beam
  double mse_ratio_single = 0.0;   ///< eq. 31 on single readings of the test draw (beam nearest each centre)
  int order = -1;                  ///< order chosen (closed form and oracle 0..n_max by AIC; joint 1..n_max)
  /// Per true landmark (index id - 1): closed form = triangulation (section 3.1), joint = refined
  /// centre; empty for the oracle; NaN components where the landmark was not estimated.
  std::vector<PositionError> landmarks;
};

struct TrialResult {
  std::array<EstimatorOutcome, kEstimators> estimators;  ///< indexed by Estimator
  int detected_landmarks = 0;      ///< landmarks matched to the truth (= L at the landmark level)
};

/// The layout of trial `trial`: depends on (seed, trial) only, and its first L landmarks do not
/// depend on L (layouts are nested). Throws std::runtime_error when the layout cannot be placed.
std::vector<Cylinder> trialLayout(const TrialConfig& config, std::uint64_t seed, std::size_t trial, int landmarks);

/// Seed of one trial's draws: a function of (study seed, cell parameters, trial) only, so a cell
/// gives the same numbers whichever study, thread or order it is run in.
std::uint64_t trialSeed(std::uint64_t seed, const Cell& cell, std::size_t trial);

/// Runs one trial: the draw of seed deriveSeed(trial_seed, 0) is calibrated, the draw of
/// deriveSeed(trial_seed, 1) (same layout and commanded path, fresh poses and noise) is the test set.
TrialResult runTrial(const TrialConfig& config, const Cell& cell, const std::vector<Cylinder>& layout,
                     std::uint64_t trial_seed, bool run_joint);

/// The calibration settings given to the estimators in a cell.
calibration::CalibrationConfig estimatorConfig(const TrialConfig& config, const Cell& cell);

}  // namespace lidarcal::studies
