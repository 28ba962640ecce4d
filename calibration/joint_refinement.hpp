// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Joint refinement (beyond Alhashimi et al. 2021): one maximum-likelihood problem over every stop's
// pose, the landmark centres, the landmark radius and the bias polynomial, from the individual beam
// readings rather than per-landmark summaries. Each reading y_i of beam angle a_i at stop k on
// landmark l is modelled as
//     y_i = f(d_i) + sigma(d_i) e_i,   d_i = distance along the beam from pose k to circle l,
// with priors tying each pose to its commanded value (sigma_s, sigma_psi; they also fix the
// gauge: translation, rotation and scale of the world), or, for a robot that never stops, the
// first pose to its commanded value and each later one to the commanded step from the one
// before (motion prior, JointConfig::motion). Solved with Ceres (robust Huber loss);
// the noise law is re-estimated from the residuals between solves (iteratively reweighted ML).
//
// Optional effect terms (JointEffects, all off by default; physical causes in docs/FORMAT.md,
// "Effects") extend the model the way `lidarcal diagnose` finds necessary:
//     y_i = f(d_i) + o_l + c (t_i - t_ref) + b (1 - cos phi_i) + sigma_i e_i,
//     d_i along the beam at angle a_i + a_0,   sigma_i = sigma_e f(d_i)^kappa (1 / cos
//     phi_i)^gamma,
// with per-landmark offsets o_l, drift c per scan t, zero-angle offset a_0, incidence phi_i of
// the beam on the pole; the outermost beam of each sighting may be a mixed pixel (a mixture with
// a uniform over [f(d), range max]); per-stop headings may be held at the commanded ones (the
// seeds' model) and the commanded steps may be scaled by (1 + s) (odometry scale).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/effect.hpp"
#include "common/landmark_observations.hpp"
#include "common/range_model.hpp"
#include "common/status.hpp"

namespace lidarcal::calibration {

/// The largest step scale |s| a fit takes (JointEffects::odometry_scale): odometry that misjudges
/// its steps by half is broken, not miscalibrated (JointProblem bounds it; diagnose does not name
/// a scale at the bound).
constexpr double kMaxStepScale = 0.5;

/// Effect terms beyond the seeds' model. Defaults: the refinement as it always was.
struct JointEffects {
  /// per-stop heading free with prior sigma_psi_rad; false: held at the commanded one
  bool estimate_heading = true;
  /// one range offset per landmark (surface, reflectivity), reported with mean zero
  bool landmark_offsets = false;
  bool drift = false;  ///< reading grows linearly with the scan index (warm-up)
  /// one zero-angle offset added to every beam angle (lidar mounted rotated)
  bool angle_offset = false;
  bool incidence_bias = false;  ///< reading grows by b (1 - cos phi), phi the incidence on the pole
  /// noise grows as (1 / cos phi)^gamma, gamma estimated between solves
  bool incidence_noise = false;
  /// noise sigma_e f(d)^kappa, kappa estimated between solves (squared law: 2)
  bool noise_exponent = false;
  /// outermost beams: mixture with a uniform, fraction estimated between solves (EM)
  bool mixed_pixels = false;
  /// commanded steps scaled by (1 + s), s estimated (the true step length differs)
  bool odometry_scale = false;
  /// Noise a Student t of nu degrees of freedom (unit variance times sigma), nu estimated between
  /// solves; the readings weighted by the t's EM weights (heavy tails; `diagnose`'s heavy_tails
  /// candidate).
  bool student_noise = false;
  /// Readings rounded to a grid (the sensor's range resolution, detected from the readings,
  /// detectReadingGrid): each reading's likelihood is the probability of its grid cell under the
  /// unrounded noise, whose scale is fitted by ML on the cells (`diagnose`'s quantisation
  /// candidate).
  bool quantised = false;
  /// Noise grows as (I_ref / I)^delta with the return intensity I of the reading (dark surfaces),
  /// delta estimated between solves; readings without an intensity keep the factor 1
  /// (`diagnose`'s dark_surface candidate).
  bool dark_noise = false;
  /// Whether a term in the mean of the readings is on (they need the extended residual).
  bool anyMean() const { return landmark_offsets || drift || angle_offset || incidence_bias; }
  /// Switches on the term that models `e` (heading_error: the per-stop heading, on by default);
  /// false when the refinement has no term for it (info(e).joint_term).
  bool enable(Effect e);
};

/// Estimates of the effect terms; neutral values for the terms that were off.
struct JointEffectEstimates {
  std::map<int, double> landmark_offset_m;  ///< per landmark id, mean zero over landmarks, metres
  double drift_m_per_scan = 0.0;            ///< c, metres per scan
  /// t_ref: scan index where the drift term is zero (mean scan of the fit)
  double drift_reference_scan = 0.0;
  double angle_offset_rad = 0.0;          ///< a_0, radians
  double incidence_bias_m = 0.0;          ///< b, metres
  double incidence_noise_exponent = 0.0;  ///< gamma
  double noise_exponent = 2.0;  ///< kappa of sigma_e f(d)^kappa (2: Alhashimi et al. 2016's law)
  double mixed_pixel_fraction = 0.0;  ///< of the outermost beams of the sightings
  double odometry_scale = 0.0;        ///< s: true steps are (1 + s) times the commanded ones
  double heading_rms_rad = 0.0;       ///< RMS of the refined minus the commanded headings, radians
  double student_dof = 0.0;           ///< nu of the Student-t noise (0: Gaussian)
  double range_grid_m = 0.0;          ///< grid the readings were rounded to (0: not rounded)
  double dark_noise_exponent = 0.0;   ///< delta of (I_ref / I)^delta
  /// I_ref: the median intensity of the readings the fit saw (0: none recorded). A fit started
  /// from estimates with a reference keeps it, so that folds and refits share one delta's meaning.
  double dark_reference_intensity = 0.0;
};

/// Least mixed-pixel fraction the refinement's EM step keeps (a fraction at it: no reading was
/// attributed to mixed pixels).
inline constexpr double kMinMixedPixelFraction = 1e-4;

/// Whether the odometry between consecutive stops enters as a motion prior.
enum class MotionPrior {
  automatic,  ///< on when continuousMotion() says the sequence never stopped (default)
  off,        ///< every stop tied to its commanded pose (stop and go, Alhashimi et al. 2021 eq. 8)
  /// the first stop tied to its commanded pose, every later one to the commanded step from the one
  /// before
  on,
};
const char* toString(MotionPrior m);

/// What a tape measure says about the range model at one measured target (REF.json `distances`
/// at some stops): the readings of the beams on it and their true distances. On a pole the tape
/// gives the distance to its centre, so each beam's distance follows from the centre (on the
/// detected bearing) and the pole radius, which the refinement estimates with the rest; on a wall
/// it is given. One residual per target, the mean reading against the mean of f over its beams,
/// because the beams of one target share its one tape error.
struct KnownRange {
  struct Beam {
    double angle_rad = 0.0;       ///< beam angle in the sensor frame, radians
    double distance_m = 0.0;      ///< true distance (walls; on a pole it follows from the radius)
    double count = 0.0;           ///< readings of this beam
    double mean_reading_m = 0.0;  ///< their mean, metres
  };
  bool pole = false;  ///< beam distances from the centre and the common radius
  double centre_x_m = 0.0, centre_y_m = 0.0;  ///< pole centre in the sensor frame, metres
  std::vector<Beam> beams;
  double tape_sigma_m = 0.002;  ///< standard deviation of the measured distance, metres
  double count() const;         ///< readings behind the mean
  double meanDistance(double radius_m) const;  ///< mean true distance of the readings, metres
  /// True distance of beam b with pole radius `radius` (any scalar type, for the Ceres cost).
  template <typename T>
  T distance(const Beam& b, const T& radius) const;
};

struct JointConfig {
  int order = 2;  ///< bias polynomial order n (>= 1)
  /// noise law re-estimated between solves: squared, polynomial or constant
  NoiseKind noise = NoiseKind::squared;
  int noise_order = 1;  ///< order of the polynomial noise law (Alhashimi et al. 2021 beta)
  /// prior std. dev. of each stop coordinate around the commanded one, metres
  double sigma_s_m = 0.02;
  double sigma_psi_rad = 0.0087;  ///< prior std. dev. of each stop heading, radians (0.5 degree)
  bool estimate_radius = true;  ///< estimate one common landmark radius (else keep the initial one)
  double huber_sigmas = 2.0;    ///< Huber threshold, in standard deviations of the reading
  /// Loss of the readings: false Huber (default), true Cauchy at the same scale (bounded
  /// influence: gross outliers, e.g. grazing beams far noisier than the model says, stop pulling).
  bool cauchy_loss = false;
  /// use beams passing within this fraction of the radius from the centre
  double lateral_fraction = 1.0;
  bool reselect = true;      ///< re-select the beams from the current estimate before every solve
  int outer_iterations = 6;  ///< noise re-estimations at most
  int max_solver_iterations = 200;  ///< Ceres iterations per solve
  bool covariance = true;           ///< compute the covariance of the bias coefficients
  /// Up to this many parameters the covariance comes from a dense SVD of the Jacobian (a
  /// pseudo-inverse if the data leave a direction free); beyond, from a sparse QR, whose memory
  /// grows with the poses instead of readings x parameters. Default 2000 (about 600 poses).
  int dense_covariance_max_parameters = 2000;
  JointEffects effects;  ///< effect terms (all off: the seeds' model plus per-stop poses)
  /// use every beam of every sighting (the caller selected them); ignores lateral_fraction
  bool keep_all_beams = false;
  /// first solve with the bias held (off when starting from a converged solution)
  bool settle_geometry = true;
  /// Keep the noise law's shape parameters (kappa, gamma, delta) at the start's values and fit
  /// only its scale: `diagnose` estimates the incidence and darkness exponents itself on a
  /// continuous recording, where a pose per scan shrinks the residuals of the readings it rests
  /// on (restricted likelihood over the poses, diagnosis/sequence.cpp).
  bool hold_noise_shape = false;
  /// One residual per beam, landmark and stop instead of one per reading: repeated scans from
  /// one pose summarised by their count and mean (the Gaussian likelihood unchanged, the cost
  /// independent of the scans per stop). Not with drift or mixed pixels. Default true.
  bool pool_repeated_scans = true;
  /// Motion prior (continuous motion: each scan its own stop, the robot driving between them).
  /// On, the first stop keeps the prior around its commanded pose (sigma_s_m, sigma_psi_rad: it
  /// fixes the gauge) and every later stop k is tied to stop k - 1 by the commanded step between
  /// them (robot frame of k - 1): each coordinate with std. dev. motion_sigma_fraction s +
  /// motion_sigma_floor_m, the heading change with motion_heading_sigma_rad_per_m s +
  /// motion_heading_floor_rad, s the step's length as its neighbours report it
  /// (motionStepLength). Odometry drift then accumulates along the path as it does on a real
  /// robot instead of being pulled back to the commanded poses. Default automatic.
  MotionPrior motion = MotionPrior::automatic;
  /// std. dev. of each step coordinate per metre of step. Default 0.1
  double motion_sigma_fraction = 0.1;
  double motion_sigma_floor_m = 0.002;  ///< plus this, metres. Default 0.002
  /// std. dev. of the heading change per metre of step, rad/m. Default 0.1 (5.7 deg/m)
  double motion_heading_sigma_rad_per_m = 0.1;
  double motion_heading_floor_rad = 0.002;  ///< plus this, radians. Default 0.002 (0.11 deg)
  /// The motion prior's std. dev. of each coordinate of a step of length `len`, metres.
  double motionStepSigma(double len) const {
    return motion_sigma_fraction * len + motion_sigma_floor_m;
  }
  /// The motion prior's std. dev. of the heading change over a step of length `len`, radians.
  double motionHeadingSigma(double len) const {
    return motion_heading_sigma_rad_per_m * len + motion_heading_floor_rad;
  }
  /// automatic: the fewest stops a continuous sequence has (below, stop and go is assumed).
  /// Default 20.
  int motion_min_stops = 20;
  /// Weight of a uniform density over the reading window mixed into every reading's likelihood
  /// (in the reported likelihood only, not in the fit), so that a few gross outliers cannot
  /// dominate a comparison of models. 0: plain Gaussian likelihood (default).
  double outlier_floor = 0.0;
  /// Surveyed landmark centres (landmark id -> centre in the frame of the commanded poses, metres),
  /// held fixed: measured geometry gives the refinement the absolute scale that self-calibration
  /// lacks (an odometry scale error is otherwise absorbed by the bias; REF.json `landmarks`).
  std::map<int, Eigen::Vector2d> known_centres;
  /// Measured sensor poses (stop index -> pose), held fixed (REF.json `stops`).
  std::map<std::size_t, Pose2> known_poses;
  /// Measured distances (REF.json `distances` at some stops): each adds the Alhashimi et al. 2016
  /// section 5 term (mean reading - mean f(d)) / sqrt(sigma(d)^2 / n + (f'(d) tape_sigma)^2) to the
  /// fit, so the tape's scale enters beside the self-calibration's geometry (and, on poles, the
  /// radius).
  std::vector<KnownRange> known_ranges;
  void validate() const;  ///< throws std::invalid_argument
};

/// The rule of MotionPrior::automatic: a sequence is continuous (the robot never stopped, each
/// scan its own stop, as imports from CARMEN, YDLIDAR or CSV odometry give) when it has at least
/// config.motion_min_stops stops and more than half of the stops with sightings have them from
/// one scan only. Stop-and-go recordings hold several scans per stop; a few stops of one scan
/// each (short tests, Alhashimi et al. 2021's study with one scan per stop) stay stop and go.
bool continuousMotion(const LandmarkObservations& obs, const JointConfig& config);

/// The length the motion prior's deviations are taken at for the step into pose k >= 1 of
/// `commanded`: the median length of its neighbours, the commanded steps k - 10 ... k + 10 but
/// itself (those that exist), when its own reported length lies within half of that median either
/// way, otherwise its own. Odometry errs in proportion to the step it measures, not to what it
/// reports; weighed at its own reported length, a step reported short weighed more than one
/// reported long, and a drive's fitted step scale came out 1.2 % long on average (odometry noise
/// 10 % of 3 cm steps, tests/calibration/test_motion_prior.cpp; docs/results/hidden-effects.md).
/// The refined step's length instead follows the reported one through the poses' share of the step
/// (it gave -0.6 %); the neighbours' median is independent of the step's own noise. A step more
/// than half again or less than half its neighbours' is the robot changing speed (or a pose left
/// out), not the odometry's noise (a tenth of the step): on CARMEN's logs a step is 0.1 to 8.5
/// times its neighbours' median, and weighed at the median such steps changed two of four verdicts.
double motionStepLength(const std::vector<Pose2>& commanded, std::size_t k);

/// Starting point (normally the closed-form calibration).
struct JointInit {
  std::vector<Pose2> poses;                ///< one per stop (commanded poses are a fine start)
  std::map<int, Eigen::Vector2d> centres;  ///< landmark id -> centre (world frame)
  double radius_m = 0.1;                   ///< common landmark radius
  RangeModel model;                        ///< bias and noise to start from
  JointEffectEstimates effects;  ///< effect terms to start from (used for the terms switched on)
};

struct JointResult {
  /// ok (converged and status.message say how settled the solution is), or why there is none:
  /// not_run (a result nobody computed, the default), too_few_readings (fewer landmark readings
  /// than four per bias parameter), no_readings (none left to fit at a solve), solver_failed.
  Status status{StatusCode::not_run, ""};
  bool ok() const { return status.ok(); }
  std::vector<Pose2> poses;                          ///< refined stop poses (one per stop when ok)
  std::map<int, Eigen::Vector2d> centres;            ///< refined landmark centres
  std::map<int, Eigen::Matrix2d> centre_covariance;  ///< per landmark, m^2 (when covariance is on)
  double radius_m = 0.0;                             ///< refined common radius
  RangeModel model;                                  ///< bias (order n) and noise law
  /// covariance of alpha_0..alpha_n, gauge fixed by the pose priors
  Eigen::MatrixXd alpha_covariance;
  /// Covariance of the estimated radius with alpha_0..alpha_n, m^2 (empty when the radius was
  /// held or the covariance not computed): an offset that trades off against the radius is not
  /// determined by the data.
  Eigen::VectorXd alpha_radius_covariance;
  double radius_variance = 0.0;      ///< variance of the estimated radius, m^2 (0 when held)
  double sigma_theta_rad = 0.0;      ///< RMS of centre-bearing residuals after refinement
  double pose_scatter_m = 0.0;       ///< RMS of refined minus commanded position (per coordinate)
  double heading_scatter_rad = 0.0;  ///< RMS of refined minus commanded heading
  std::size_t readings = 0;          ///< beam readings used
  /// residuals they made in the last solve (fewer when repeated scans are pooled)
  std::size_t reading_residuals = 0;
  double residual_rms_m = 0.0;      ///< RMS of reading minus f(predicted distance)
  std::vector<double> distances_m;  ///< predicted distance of every reading used, at the solution
  std::vector<double> readings_m;   ///< the readings themselves (same order)
  std::size_t outliers = 0;         ///< readings beyond the Huber threshold at the end
  double neg_log_likelihood = 0.0;  ///< Gaussian NLL of the readings at the solution
  /// NLL of the commanded stop positions as measurements of the refined ones (Alhashimi et al. 2021
  /// eq. 8, sigma_s_m; with the odometry scale, of the scaled commanded path); with the motion
  /// prior, of the first stop's position and of the commanded steps' translations. Headings not
  /// included.
  double prior_neg_log_likelihood = 0.0;
  bool motion_prior = false;     ///< the motion prior was used (JointConfig::motion)
  double aic = 0.0;              ///< 2 k + 2 NLL, k = bias + noise + radius parameters
  double bic = 0.0;              ///< k ln N + 2 NLL
  int solver_iterations = 0;     ///< Ceres iterations, all solves
  int outer_iterations = 0;      ///< noise re-estimations done
  bool converged = false;        ///< last solve converged and the noise settled
  JointEffectEstimates effects;  ///< effect terms (neutral when off)
  /// parameters of the effect terms switched on (heading: one per stop)
  int effect_parameters = 0;
  double window_min_m = 0.0;  ///< reading window of the outlier floor and the mixed pixels, metres
  double window_max_m = 0.0;  ///< (sensor window, or 1.25 x the largest reading when unknown)
};

JointResult refineJoint(const LandmarkObservations& obs, const JointInit& init,
                        const JointConfig& config);

/// A start at a fitted solution: its poses, centres, radius, range model and effect terms.
JointInit initFrom(const JointResult& r);

/// One beam reading evaluated under a fitted joint model.
struct JointReading {
  std::size_t sighting = 0;  ///< index into LandmarkObservations::sightings
  std::size_t stop = 0;      ///< stop index
  std::size_t scan = 0;      ///< scan index
  int landmark = 0;          ///< landmark id
  std::uint32_t beam = 0;    ///< beam index in its scan
  double angle_rad = 0.0;    ///< nominal beam angle in the sensor frame, radians
  double y_m = 0.0;          ///< the reading, metres
  double d_m = 0.0;          ///< predicted true distance along the beam, metres
  /// signed miss distance of the beam from the centre over the radius (0 centre, +-1 tangent)
  double lateral = 0.0;
  double cos_incidence = 1.0;  ///< cosine of the incidence on the pole (clamped at 0.05)
  double darkness = 0.0;       ///< ln(I_ref / I) of its intensity (0: none recorded)
  bool edge = false;     ///< first or last beam of its sighting (depth discontinuity next to it)
  double mean_m = 0.0;   ///< predicted reading: f(d) plus the effect terms, metres
  double sigma_m = 0.0;  ///< predicted standard deviation, metres
  /// of the reading under the model (with its mixed-pixel and outlier terms), nats
  double log_likelihood = 0.0;
};

/// Every finite beam of the sightings of `obs` whose landmark and stop the fit knows, under the
/// fitted model (poses, centres, radius, bias, noise, effects). Used for residuals and for
/// held-out likelihoods (obs may hold scans the fit never saw, at stops it refined).
std::vector<JointReading> evaluateJoint(const LandmarkObservations& obs, const JointResult& fit,
                                        const JointConfig& config);

/// The law of a reading beyond its mean and standard deviation, as refineJoint fits it.
struct ReadingLaw {
  double mixed_fraction = 0.0;  ///< weight of a uniform over [mean, window_max] (mixed pixels)
  double outlier_floor = 0.0;   ///< weight of a uniform over the window
  double window_min_m = 0.0, window_max_m = 0.0;
  /// > 2: a Student t of that many degrees of freedom and standard deviation sigma instead of
  /// the Gaussian.
  double student_dof = 0.0;
  /// > 0: readings are rounded to that grid, and the core density is the noise's probability
  /// of y's cell [y - q/2, y + q/2] over q (the density of the reading plus a uniform rounding
  /// error: comparable with a continuous model's density at a reading spread over its cell).
  double grid_m = 0.0;
};

/// Log-likelihood of a reading y with predicted mean and standard deviation under `law`, as
/// refineJoint reports it: the core density (Gaussian or Student t, rounded or not) mixed with
/// the law's uniforms.
double readingLogLikelihood(double y_m, double mean_m, double sigma_m, const ReadingLaw& law);

/// Log-density of a reading y under the noise alone: Gaussian of mean and standard deviation
/// sigma, or a Student t of that standard deviation (`student_dof` > 2); with `grid_m` > 0 the
/// probability of y's grid cell under it, over the grid (the rounded model).
double coreLogDensity(double y_m, double mean_m, double sigma_m, double student_dof, double grid_m);

/// Log-density of a Student t with nu > 2 degrees of freedom, mean 0 and standard deviation
/// sigma, at x (the simulator's unit-variance t scaled by sigma).
double studentLogDensity(double x, double sigma, double nu);

}  // namespace lidarcal::calibration

#include "calibration/joint_refinement_impl.hpp"
