// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One Monte Carlo trial of the Alhashimi et al. 2021 study (sections 4.1-4.2): simulate a
// calibration run over a landmark layout, calibrate it with the paper's closed form (triangulation
// + LS + AIC), our joint refinement and the oracle (the same LS + AIC against the true distances),
// and score each on a fresh draw of the same layout with the MSE ratio (eq. 31) on three test sets,
// with the order by AIC and by parsimonious AIC read from each estimator's table of fitted orders,
// beside the ratio the simulated sensor's own bias gives (the ceiling). The landmark positions of
// the triangulation (section 3.1) and of the joint refinement are scored against the truth.

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "calibration/calibrate.hpp"
#include "common/scene.hpp"
#include "studies/placement.hpp"

namespace lidarcal::studies {

/// How the scans are produced.
enum class Level {
  /// Alhashimi et al. 2021 eqs. 3, 5, 8 per landmark, beams ray-cast on each landmark (fast)
  landmark,
  scan,  ///< whole scans ray-cast, landmarks found by the detector (detection in the loop)
};
const char* toString(Level level);
bool parseLevel(const std::string& name, Level& level);

/// What the angular noise sigma_theta of a cell perturbs, and so what each estimator sees.
enum class AngleNoise {
  /// The robot's heading at each stop (default): every beam and every centre bearing of the stop
  /// turns with it, as on a real robot. The closed form sees, per landmark, independent bearing
  /// errors across stops (eq. 5); the joint refinement sees the same beams and estimates one
  /// heading per stop, shared by the landmarks.
  heading,
  /// Eq. 5 on everything the sensor reports of landmark l at stop k: its centre bearing and the
  /// angle of each of its beams turn by one v_lk ~ N(0, sigma_theta^2), independently per
  /// landmark and stop. Both estimators see it; neither model has a term for it.
  beams,
  /// Eq. 5 on the detected centre bearing only; the beams' angles stay exact. The closed form
  /// (which triangulates centre bearings) sees the noise; the joint refinement, which fits the
  /// beam angles, does not (its ratio cannot depend on sigma_theta). Kept for comparison: it was
  /// the landmark level's default before, and no real sensor works this way.
  bearing,
};
const char* toString(AngleNoise noise);
bool parseAngleNoise(const std::string& name, AngleNoise& noise);

/// The simulated sensor's noise law.
enum class NoiseLaw {
  /// Alhashimi et al. 2021 section 4.1: sigma(d) = |sum beta_i d^i|, beta = 0.05 alpha (5 % of
  /// f(d))
  paper,
  /// Alhashimi et al. 2016 eq. 1: sigma(d) = sigma_e f(d)^2, sigma_e so that sigma(3 m) is the
  /// paper law's
  squared,
};
const char* toString(NoiseLaw law);
bool parseNoiseLaw(const std::string& name, NoiseLaw& law);

/// Order rules the estimators are compared under: each estimator's table of fitted orders is
/// read with both, so the three are always compared under the same rule.
enum class Rule {
  aic = 0,  ///< smallest AIC (Alhashimi et al. 2021 section 3.2)
  /// smallest order whose AIC is within 2 of the smallest (Burnham & Anderson)
  aic_parsimonious = 1,
};
constexpr std::size_t kRules = 2;
const char* toString(Rule r);

/// The test sets eq. 31 is evaluated on: readings of a fresh draw of the same layout.
enum class TestSet {
  beams = 0,  ///< every beam on a landmark, its readings averaged over the stop's scans
  /// the beam nearest each landmark's centre (by the truth), averaged over the stop's scans
  centre = 1,
  /// single readings of the beam nearest each detected centre (one per landmark and scan)
  single = 2,
};
constexpr std::size_t kTestSets = 3;

/// One point of a study grid.
struct Cell {
  int landmarks = 5;        ///< number of landmarks L
  double sigma_s_m = 0.01;  ///< std. dev. of each stop coordinate (eq. 8), metres
  /// std. dev. of the angle noise (eq. 5), radians (2 degrees)
  double sigma_theta_rad = 0.03490658503988659;
};

/// The three estimators, in output order.
enum class Estimator { closed_form = 0, joint = 1, oracle = 2 };
constexpr std::size_t kEstimators = 3;
const char* toString(Estimator e);

struct TrialConfig {
  Level level = Level::landmark;  ///< simulation level
  /// Angle-noise model (default heading). The scan level supports heading only (the detector's
  /// bearings carry their own noise).
  AngleNoise angle_noise = AngleNoise::heading;
  /// stops (20), step (0.15 m), scans per stop (10); sigmas from the cell
  PathSpec path = defaultPath();
  /// Alhashimi et al. 2021 section 4.1: n = 2, alpha, beta = 0.05 alpha; window 0.2-6 m
  RangeModel sensor = paperSensor();
  /// the law of the simulated noise (sensor.noise is replaced for squared)
  NoiseLaw noise_law = NoiseLaw::paper;
  /// Multiplies the noise coefficients beta of `sensor` (1: the paper's 5 % of the range). The
  /// detector cannot find 12 cm poles through that much noise beyond about a metre, so scan-level
  /// studies run with less (the command's default there is 0.2).
  double noise_scale = 1.0;
  PlacementConfig placement;  ///< random layouts
  int max_order = 3;          ///< n_max of the order selection (all estimators)
  /// noise re-estimations of the joint refinement (library default 6)
  int joint_outer_iterations = 3;
  bool joint_average_scans = true;  ///< joint refinement on per-stop beam averages (averageScans)
  int scan_beams = 360;             ///< scan level: beams per sweep (1 degree apart)
  double min_sigma_s_m = 0.001;     ///< floor of the sigma_s the estimators are told, metres
  /// floor of the sigma_theta they are told (0.1 degree)
  double min_sigma_theta_rad = 0.0017453292519943296;
  void validate() const;  ///< throws std::invalid_argument

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

/// One estimator's model read with one order rule.
struct RuleOutcome {
  /// order the rule picks (closed form and oracle 0..n_max, joint 1..n_max); -1: no model
  int order = -1;
  /// Eq. 31 on each test set (TestSet), with the fitted order's bias (order 0: order 1's, which
  /// can be inverted); NaN without a model.
  std::array<double, kTestSets> mse_ratio{std::numeric_limits<double>::quiet_NaN(),
                                          std::numeric_limits<double>::quiet_NaN(),
                                          std::numeric_limits<double>::quiet_NaN()};
};

struct EstimatorOutcome {
  bool ran = false;                       ///< the estimator was run in this trial
  bool ok = false;                        ///< it produced a model (status ok)
  std::array<RuleOutcome, kRules> rules;  ///< indexed by Rule
  /// Per true landmark (index id - 1): closed form = triangulation (section 3.1), joint = refined
  /// centre; empty for the oracle; NaN components where the landmark was not estimated.
  std::vector<PositionError> landmarks;
};

struct TrialResult {
  std::array<EstimatorOutcome, kEstimators> estimators;  ///< indexed by Estimator
  /// Eq. 31 on each test set with the simulated sensor's own bias (LS inversion): what a perfect
  /// calibration would give, the ceiling of every estimator.
  std::array<double, kTestSets> ceiling{std::numeric_limits<double>::quiet_NaN(),
                                        std::numeric_limits<double>::quiet_NaN(),
                                        std::numeric_limits<double>::quiet_NaN()};
  int detected_landmarks = 0;  ///< landmarks matched to the truth (= L at the landmark level)
};

/// The layout of trial `trial`: depends on (seed, trial) only, and its first L landmarks do not
/// depend on L (layouts are nested). Throws std::runtime_error when the layout cannot be placed.
std::vector<Cylinder> trialLayout(const TrialConfig& config, std::uint64_t seed, std::size_t trial,
                                  int landmarks);

/// Seed of one trial's draws: a function of (study seed, cell parameters, trial) only, so a cell
/// gives the same numbers whichever study, thread or order it is run in.
std::uint64_t trialSeed(std::uint64_t seed, const Cell& cell, std::size_t trial);

/// Runs one trial: the draw of seed deriveSeed(trial_seed, 0) is calibrated, the draw of
/// deriveSeed(trial_seed, 1) (same layout and commanded path, fresh poses and noise) is the test
/// set.
TrialResult runTrial(const TrialConfig& config, const Cell& cell,
                     const std::vector<Cylinder>& layout, std::uint64_t trial_seed, bool run_joint);

/// The simulated sensor of a configuration (noise law and noise_scale applied).
RangeModel simulatedSensor(const TrialConfig& config);

/// The order `rule` picks from a model's table of fitted orders (admissible rows only); -1 when
/// the table is empty.
int ruleOrder(const CalibrationModel& model, Rule rule);

/// The calibration settings given to the estimators in a cell.
calibration::CalibrationConfig estimatorConfig(const TrialConfig& config, const Cell& cell);

}  // namespace lidarcal::studies
