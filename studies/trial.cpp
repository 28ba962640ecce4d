// SPDX-License-Identifier: BSD-3-Clause
#include "studies/trial.hpp"

#include <cmath>
#include <initializer_list>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>

#include "calibration/evaluation.hpp"
#include "calibration/inversion.hpp"
#include "common/rng.hpp"
#include "common/stats_util.hpp"
#include "studies/draw.hpp"
#include "studies/scan_level.hpp"

namespace lidarcal::studies {
namespace {

/// Stream tags, so the layout, the cells and the draws never share a random stream.
constexpr std::uint64_t kLayoutTag = 0x6c61796f7574ULL;  // "layout"
constexpr std::uint64_t kCellTag = 0x63656c6cULL;        // "cell"

/// Pairs of the oracle: the readings the closed form uses (the beam nearest each detected
/// centre, averaged per landmark, stop and third as in calibration::closedFormPairs) with
/// their true distances in place of the triangulated ones.
std::vector<calibration::RangePair> oraclePairs(const Draw& draw) {
  std::map<std::size_t, std::set<std::size_t>> scans_of_stop;
  for (const auto& s : draw.obs.sightings) scans_of_stop[s.stop].insert(s.scan);
  std::map<std::size_t, std::size_t> position;
  for (const auto& [stop, scans] : scans_of_stop) {
    std::size_t i = 0;
    for (std::size_t scan : scans) position[scan] = i++;
  }
  struct Acc {
    double d = 0.0, y = 0.0;
    int n = 0;
  };
  std::map<std::tuple<int, std::size_t, int>, Acc> groups;
  for (std::size_t i = 0; i < draw.obs.sightings.size(); ++i) {
    const Sighting& s = draw.obs.sightings[i];
    if (s.beams.empty()) continue;
    const std::size_t j = calibration::centralBeam(s);
    const double t = draw.truth_m[i][j], y = s.beams[j].range_m;
    if (!std::isfinite(t) || !std::isfinite(y)) continue;
    const int part = scans_of_stop.at(s.stop).size() >= 3
                         ? static_cast<int>(position.at(s.scan) % 3)
                         : static_cast<int>((s.stop + static_cast<std::size_t>(s.landmark)) % 3);
    Acc& a = groups[{s.landmark, s.stop, part}];
    a.d += t;
    a.y += y;
    ++a.n;
  }
  std::vector<calibration::RangePair> pairs;
  for (const auto& [key, a] : groups) pairs.push_back({a.d / a.n, a.y / a.n, std::get<2>(key)});
  return pairs;
}

/// The test sets (TestSet): truth and raw readings of each. Every landmark beam's readings
/// averaged per (stop, landmark, beam) (one beam at one stop keeps its true distance over the
/// stop's scans); the beam nearest each centre by the truth, averaged per (stop, landmark); single
/// readings of the beam nearest each detected centre (one per landmark and scan, as eq. 3 draws
/// them).
struct TestReadings {
  std::vector<double> truth, raw;
};
using TestSets = std::array<TestReadings, kTestSets>;

TestSets testSets(const Draw& draw) {
  TestSets t;
  struct Acc {
    double d = 0.0, y = 0.0;
    int n = 0;
    void add(double truth, double reading) {
      d += truth;
      y += reading;
      ++n;
    }
  };
  std::map<std::tuple<std::size_t, int, std::uint32_t>, Acc> beams;
  for (const TruthReading& r : truthReadings(draw))
    beams[{r.stop, r.landmark, r.beam}].add(r.true_m, r.range_m);
  for (const auto& [key, a] : beams) {
    t[static_cast<std::size_t>(TestSet::beams)].truth.push_back(a.d / a.n);
    t[static_cast<std::size_t>(TestSet::beams)].raw.push_back(a.y / a.n);
  }
  std::map<std::pair<std::size_t, int>, Acc> centres;
  for (std::size_t i = 0; i < draw.obs.sightings.size(); ++i) {
    const Sighting& s = draw.obs.sightings[i];
    if (s.beams.empty()) continue;
    const int id = s.landmark > 0 && static_cast<std::size_t>(s.landmark) < draw.true_id.size()
                       ? draw.true_id[s.landmark]
                       : 0;
    std::size_t nearest = s.beams.size();  // smallest true distance: the beam through the centre
    for (std::size_t j = 0; j < s.beams.size(); ++j)
      if (std::isfinite(draw.truth_m[i][j]) && std::isfinite(s.beams[j].range_m) &&
          (nearest == s.beams.size() || draw.truth_m[i][j] < draw.truth_m[i][nearest]))
        nearest = j;
    if (id > 0 && nearest < s.beams.size())
      centres[{s.stop, id}].add(draw.truth_m[i][nearest], s.beams[nearest].range_m);
    const std::size_t j = calibration::centralBeam(s);
    if (!std::isfinite(draw.truth_m[i][j]) || !std::isfinite(s.beams[j].range_m)) continue;
    t[static_cast<std::size_t>(TestSet::single)].truth.push_back(draw.truth_m[i][j]);
    t[static_cast<std::size_t>(TestSet::single)].raw.push_back(s.beams[j].range_m);
  }
  for (const auto& [key, a] : centres) {
    t[static_cast<std::size_t>(TestSet::centre)].truth.push_back(a.d / a.n);
    t[static_cast<std::size_t>(TestSet::centre)].raw.push_back(a.y / a.n);
  }
  return t;
}

/// Corrects readings with a model (LS inversion, Alhashimi et al. 2021 eq. 30); a reading the model
/// cannot invert is left as it is (a filter in use has nothing better to report).
std::vector<double> correct(const calibration::RangeInverter& inv, const std::vector<double>& raw) {
  std::vector<double> out(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) {
    const auto d = inv.invert(raw[i]);
    out[i] = d ? *d : raw[i];
  }
  return out;
}

/// Eq. 31 of a bias polynomial on every test set.
std::array<double, kTestSets> ratios(const std::vector<double>& alpha, const TestSets& tests,
                                     const LandmarkObservations& obs) {
  RangeModel model;
  model.bias.alpha = alpha;
  model.range_min_m = obs.range_min_m;
  model.range_max_m = obs.range_max_m;
  const calibration::RangeInverter inv(
      model, calibration::inversionWindow(model, calibration::InversionMethod::ls));
  std::array<double, kTestSets> out{};
  for (std::size_t k = 0; k < kTestSets; ++k)
    out[k] = calibration::compareRanges(tests[k].truth, tests[k].raw, correct(inv, tests[k].raw))
                 .mse_ratio;
  return out;
}

/// Scores a model with both order rules: the bias of the order each picks from the model's table.
void score(EstimatorOutcome& o, const CalibrationModel& m, const TestSets& tests,
           const LandmarkObservations& obs) {
  o.ok = m.status.ok();
  if (!o.ok) return;
  for (std::size_t r = 0; r < kRules; ++r) {
    RuleOutcome& out = o.rules[r];
    out.order = ruleOrder(m, static_cast<Rule>(r));
    // order 0 cannot be inverted: the calibration uses order 1
    const int used = std::max(out.order, 1);
    for (const OrderRow& row : m.orders)
      if (row.order == used) out.mse_ratio = ratios(row.alpha, tests, obs);
  }
}

/// Position errors of a model's landmarks against the layout, in each landmark's frame.
std::vector<PositionError> positionErrors(const CalibrationModel& m, const Draw& draw,
                                          const std::vector<Cylinder>& layout) {
  std::vector<PositionError> out(layout.size(), PositionError{kNaN, kNaN});
  double mx = 0.0, my = 0.0;
  for (const Pose2& p : draw.obs.commanded) {
    mx += p.x_m;
    my += p.y_m;
  }
  mx /= static_cast<double>(draw.obs.commanded.size());
  my /= static_cast<double>(draw.obs.commanded.size());
  for (const CalibratedLandmark& l : m.landmarks) {
    if (!l.ok() || l.id <= 0 || static_cast<std::size_t>(l.id) >= draw.true_id.size()) continue;
    const int id = draw.true_id[static_cast<std::size_t>(l.id)];
    if (id <= 0) continue;
    const Cylinder& c = layout[static_cast<std::size_t>(id - 1)];
    const double ux = c.x_m - mx, uy = c.y_m - my, n = std::hypot(ux, uy);
    const double ex = l.x_m - c.x_m, ey = l.y_m - c.y_m;
    out[static_cast<std::size_t>(id - 1)] =
        PositionError{(ex * ux + ey * uy) / n, (-ex * uy + ey * ux) / n};
  }
  return out;
}

/// Runs an estimator; a std::exception (a degenerate draw the stage does not report as a
/// status) becomes a failed model, counted as a failure of the trial, not of the study.
template <typename F>
CalibrationModel guarded(F&& f) {
  try {
    return f();
  } catch (const std::exception& e) {
    CalibrationModel m;
    m.status.code = StatusCode::exception;
    m.status.message = e.what();
    return m;
  }
}

}  // namespace

const char* toString(Level level) { return level == Level::landmark ? "landmark" : "scan"; }

bool parseLevel(const std::string& name, Level& level) {
  if (name == "landmark")
    level = Level::landmark;
  else if (name == "scan")
    level = Level::scan;
  else
    return false;
  return true;
}

const char* toString(AngleNoise noise) {
  switch (noise) {
    case AngleNoise::heading:
      return "heading";
    case AngleNoise::beams:
      return "beams";
    case AngleNoise::bearing:
      return "bearing";
  }
  return "unknown";
}

namespace {
/// The value of `all` whose name is `name`, if any.
template <typename E>
bool parseByName(const std::string& name, std::initializer_list<E> all, E& out) {
  for (E e : all)
    if (name == toString(e)) {
      out = e;
      return true;
    }
  return false;
}
}  // namespace

bool parseAngleNoise(const std::string& name, AngleNoise& noise) {
  return parseByName(name, {AngleNoise::heading, AngleNoise::beams, AngleNoise::bearing}, noise);
}

const char* toString(NoiseLaw law) { return law == NoiseLaw::paper ? "paper" : "squared"; }

bool parseNoiseLaw(const std::string& name, NoiseLaw& law) {
  return parseByName(name, {NoiseLaw::paper, NoiseLaw::squared}, law);
}

const char* toString(Rule r) { return r == Rule::aic ? "aic" : "aic-parsimonious"; }

int ruleOrder(const CalibrationModel& model, Rule rule) {
  const OrderRow* best = nullptr;
  for (const OrderRow& row : model.orders)
    if (row.invertible && std::isfinite(row.aic) && (!best || row.aic < best->aic)) best = &row;
  if (!best) return -1;
  if (rule == Rule::aic) return best->order;
  int order = best->order;
  for (const OrderRow& row : model.orders)
    if (row.invertible && row.aic <= best->aic + 2.0) order = std::min(order, row.order);
  return order;
}

RangeModel simulatedSensor(const TrialConfig& config) {
  RangeModel sensor = config.sensor;
  if (config.noise_law == NoiseLaw::squared) {
    const double at3 = sensor.noise.stddev(3.0, sensor.bias);
    const double f3 = sensor.bias(3.0);
    sensor.noise = NoiseModel{};
    sensor.noise.kind = NoiseKind::squared;
    sensor.noise.sigma_e = at3 / (f3 * f3);
  }
  for (double& b : sensor.noise.beta) b *= config.noise_scale;
  sensor.noise.sigma_e *= config.noise_scale;
  return sensor;
}

const char* toString(Estimator e) {
  switch (e) {
    case Estimator::closed_form:
      return "closed_form";
    case Estimator::joint:
      return "joint";
    case Estimator::oracle:
      return "oracle";
  }
  return "unknown";
}

PathSpec TrialConfig::defaultPath() {
  PathSpec p;
  p.stops = 20;
  p.step_m = 0.15;
  p.scans_per_stop = 10;
  return p;
}

RangeModel TrialConfig::paperSensor() {
  RangeModel m;
  m.bias.alpha = {0.0525, 0.8838, 0.0584};
  m.noise.kind = NoiseKind::polynomial;
  m.noise.beta = {0.05 * 0.0525, 0.05 * 0.8838, 0.05 * 0.0584};
  m.range_min_m = 0.2;
  m.range_max_m = 6.0;
  return m;
}

void TrialConfig::validate() const {
  if (path.stops < 3) throw std::invalid_argument("TrialConfig: at least 3 stops");
  if (!(path.step_m > 0.0)) throw std::invalid_argument("TrialConfig: step_m must be positive");
  if (path.scans_per_stop < 1)
    throw std::invalid_argument("TrialConfig: scans_per_stop must be >= 1");
  if (max_order < 1 || max_order > 6)
    throw std::invalid_argument("TrialConfig: max_order must be 1..6");
  if (joint_outer_iterations < 1)
    throw std::invalid_argument("TrialConfig: joint_outer_iterations must be >= 1");
  if (level == Level::scan && angle_noise != AngleNoise::heading)
    throw std::invalid_argument(
        "TrialConfig: the scan level models the angle noise as heading noise only");
  if (scan_beams < 8) throw std::invalid_argument("TrialConfig: scan_beams must be >= 8");
  if (!(noise_scale >= 0.0)) throw std::invalid_argument("TrialConfig: noise_scale must be >= 0");
  if (!(min_sigma_s_m > 0.0) || !(min_sigma_theta_rad > 0.0))
    throw std::invalid_argument("TrialConfig: the sigma floors must be positive");
  placement.validate();
}

std::vector<Cylinder> trialLayout(const TrialConfig& config, std::uint64_t seed, std::size_t trial,
                                  int landmarks) {
  auto rng = makeRng(deriveSeed(seed, kLayoutTag), trial);
  PlacementConfig p = config.placement;
  return placeLandmarks(config.path, landmarks, p, rng);
}

std::uint64_t trialSeed(std::uint64_t seed, const Cell& cell, std::size_t trial) {
  // Parameters on fixed integer grids (micrometres, microradians) so the key is exact.
  std::uint64_t key = deriveSeed(seed, kCellTag);
  key = deriveSeed(key, static_cast<std::uint64_t>(cell.landmarks));
  key = deriveSeed(key, static_cast<std::uint64_t>(std::llround(cell.sigma_s_m * 1e6)));
  key = deriveSeed(key, static_cast<std::uint64_t>(std::llround(cell.sigma_theta_rad * 1e6)));
  return deriveSeed(key, trial);
}

calibration::CalibrationConfig estimatorConfig(const TrialConfig& config, const Cell& cell) {
  calibration::CalibrationConfig cc;
  cc.max_order = config.max_order;
  cc.threads = 1;                    // the trials already run on every core
  cc.noise = NoiseKind::polynomial;  // the paper's noise law (eq. 3)
  cc.closed_form_rule = calibration::OrderRule::aic;
  // the model's own order; both rules are read from its table
  cc.joint_rule = calibration::JointOrderRule::aic;
  const double s = std::max(cell.sigma_s_m, config.min_sigma_s_m);
  const double a = std::max(cell.sigma_theta_rad, config.min_sigma_theta_rad);
  cc.triangulation.sigma_s_m = s;
  cc.triangulation.sigma_theta_rad = a;
  cc.joint.sigma_s_m = s;
  cc.joint.sigma_psi_rad =
      config.angle_noise == AngleNoise::heading ? a : config.min_sigma_theta_rad;
  cc.joint.noise_order = std::max(1, static_cast<int>(config.sensor.noise.beta.size()) - 1);
  // Stop and go by construction: the per-stop averages (averageScans) hold one scan per stop,
  // which the automatic rule would take for continuous motion.
  cc.joint.motion = calibration::MotionPrior::off;
  cc.joint.outer_iterations = config.joint_outer_iterations;
  cc.joint.covariance = false;
  return cc;
}

TrialResult runTrial(const TrialConfig& config, const Cell& cell,
                     const std::vector<Cylinder>& layout, std::uint64_t trial_seed,
                     bool run_joint) {
  PathSpec path = config.path;
  path.sigma_s_m = cell.sigma_s_m;
  path.sigma_psi_rad = config.angle_noise == AngleNoise::heading ? cell.sigma_theta_rad : 0.0;
  const double bearing_noise =
      config.angle_noise == AngleNoise::heading ? 0.0 : cell.sigma_theta_rad;
  const bool rotate_beams = config.angle_noise == AngleNoise::beams;
  const RangeModel sensor = simulatedSensor(config);
  const std::uint64_t calib_seed = deriveSeed(trial_seed, 0), test_seed = deriveSeed(trial_seed, 1);
  Draw calib, test;
  if (config.level == Level::landmark) {
    calib = drawLandmarkLevel(layout, path, sensor, bearing_noise, calib_seed, rotate_beams);
    test = drawLandmarkLevel(layout, path, sensor, bearing_noise, test_seed, rotate_beams);
  } else {
    const ScanLevelConfig sc = scanLevelConfig(config);
    calib = drawScanLevel(layout, path, sensor, sc, calib_seed, true);
    test = drawScanLevel(layout, path, sensor, sc, test_seed, false);
  }
  const TestSets tests = testSets(test);

  TrialResult r;
  for (std::size_t l = 1; l < calib.true_id.size(); ++l)
    r.detected_landmarks += calib.true_id[l] > 0;
  r.ceiling = ratios(sensor.bias.alpha, tests, calib.obs);
  calibration::CalibrationConfig cc = estimatorConfig(config, cell);

  EstimatorOutcome& cf = r.estimators[static_cast<std::size_t>(Estimator::closed_form)];
  cc.method = calibration::Method::closed_form;
  const CalibrationModel cfm = guarded([&] { return calibration::calibrate(calib.obs, cc); });
  cf.ran = true;
  score(cf, cfm, tests, calib.obs);
  cf.landmarks = positionErrors(cfm, calib, layout);

  EstimatorOutcome& jt = r.estimators[static_cast<std::size_t>(Estimator::joint)];
  if (run_joint) {
    cc.method = calibration::Method::joint;
    const CalibrationModel jm = guarded([&] {
      return calibration::calibrate(
          config.joint_average_scans ? averageScans(calib.obs) : calib.obs, cc);
    });
    jt.ran = true;
    score(jt, jm, tests, calib.obs);
    if (jm.status.ok())
      jt.landmarks = positionErrors(jm, calib, layout);
    else
      jt.landmarks.assign(layout.size(), PositionError{kNaN, kNaN});
  }

  EstimatorOutcome& orc = r.estimators[static_cast<std::size_t>(Estimator::oracle)];
  const CalibrationModel om = guarded([&] {
    return calibration::calibrateAgainstTruth(oraclePairs(calib), cc, {}, calib.obs.range_min_m,
                                              calib.obs.range_max_m);
  });
  orc.ran = true;
  score(orc, om, tests, calib.obs);
  return r;
}

}  // namespace lidarcal::studies
