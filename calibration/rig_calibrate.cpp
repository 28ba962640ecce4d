// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/rig_calibrate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>

#include "calibration/plausibility.hpp"
#include "calibration/rig_problem.hpp"
#include "common/number_text.hpp"

namespace lidarcal::calibration {
namespace {

using rig::FitSetup;

/// How far the recorded poses of the stops with sightings spread: travel (metres) and heading span
/// (radians).
struct Spread {
  double travel_m = 0.0, turn_rad = 0.0;
};
Spread recordedSpread(const RigObservations& obs, const std::vector<bool>& seen) {
  Spread s;
  const Pose2* first = nullptr;
  double lo = 0.0, hi = 0.0;
  for (std::size_t k = 0; k < obs.vehicle.size(); ++k) {
    if (!seen[k]) continue;
    const Pose2& p = obs.vehicle[k];
    if (!first) first = &p;
    const double turn = wrapAngle(p.yaw_rad - first->yaw_rad);
    lo = std::min(lo, turn), hi = std::max(hi, turn);
    for (std::size_t j = 0; j < k; ++j)
      if (seen[j])
        s.travel_m = std::max(s.travel_m,
                              std::hypot(p.x_m - obs.vehicle[j].x_m, p.y_m - obs.vehicle[j].y_m));
  }
  s.turn_rad = hi - lo;
  return s;
}

/// Union-find over stops and sensors joined by the poles they share.
struct Components {
  std::vector<std::size_t> parent;
  explicit Components(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::size_t find(std::size_t i) { return parent[i] == i ? i : parent[i] = find(parent[i]); }
  void join(std::size_t a, std::size_t b) { parent[find(a)] = find(b); }
};

/// The `count` stops or sensors (`of`: RigSighting::stop or ::sensor) grouped by the poles they
/// share.
Components joinedByPoles(const RigObservations& obs, std::size_t count,
                         std::size_t RigSighting::*of) {
  std::map<int, std::size_t> first;
  Components c(count);
  for (const RigSighting& s : obs.sightings) {
    const auto [it, fresh] = first.emplace(s.pole, s.*of);
    if (!fresh) c.join(s.*of, it->second);
  }
  return c;
}

/// Without recorded poses, one stop of each group of stops joined by poles is held: the gauge.
std::vector<bool> heldStops(const RigObservations& obs) {
  std::vector<bool> held(obs.vehicle.size(), false);
  if (obs.vehicle_known) return held;
  Components c = joinedByPoles(obs, obs.vehicle.size(), &RigSighting::stop);
  std::set<std::size_t> done;
  for (const RigSighting& s : obs.sightings)
    if (done.insert(c.find(s.stop)).second) held[s.stop] = true;
  return held;
}

/// Sensors not joined to the reference through poles both see (any stop).
std::vector<std::size_t> unlinkedSensors(const RigObservations& obs, std::size_t reference) {
  Components c = joinedByPoles(obs, obs.sensors.size(), &RigSighting::sensor);
  std::vector<std::size_t> out;
  for (std::size_t s = 0; s < obs.sensors.size(); ++s)
    if (c.find(s) != c.find(reference)) out.push_back(s);
  return out;
}

/// The rule of MotionPrior::automatic for a rig: enough stops, most of them one scan per sensor.
bool continuousRig(const RigObservations& obs, const RigConfig& config) {
  if (!obs.vehicle_known ||
      obs.vehicle.size() < static_cast<std::size_t>(std::max(1, config.motion_min_stops)))
    return false;
  // (stop, sensor) -> scans
  std::map<std::pair<std::size_t, std::size_t>, std::set<std::size_t>> scans;
  for (const RigSighting& s : obs.sightings) scans[{s.stop, s.sensor}].insert(s.scan);
  std::size_t single = 0;
  for (const auto& [key, v] : scans) single += v.size() == 1;
  return !scans.empty() && 2 * single > scans.size();
}

/// One fit; `selection` receives the pooled beams it fitted.
RigResult fitOnce(const RigObservations& obs, const RigConfig& config, const FitSetup& setup,
                  std::vector<std::size_t>* selection) {
  rig::RigProblem problem(obs, config, setup);
  RigResult r = problem.run();
  if (selection) *selection = problem.selected();
  return r;
}

/// One fit with every order and flip set; the best of the flips for sensors whose flip is unknown.
RigResult fitWithFlips(const RigObservations& obs, const RigConfig& config, FitSetup setup,
                       std::vector<std::size_t>* selection = nullptr) {
  RigResult best = fitOnce(obs, config, setup, selection);
  for (std::size_t s = 0; s < obs.sensors.size(); ++s) {
    if (obs.sensors[s].prior_known || !config.estimate_unknown_flips) continue;
    FitSetup other = setup;
    other.flips[s] = -setup.flips[s];
    std::vector<std::size_t> other_selection;
    RigResult alt = fitOnce(obs, config, other, &other_selection);
    const bool alt_better =
        alt.ok() && (!best.ok() || alt.neg_log_likelihood < best.neg_log_likelihood);
    // One flip without a solution: the other is the only one the data allow.
    const double llr = best.ok() && alt.ok()
                           ? std::abs(alt.neg_log_likelihood - best.neg_log_likelihood)
                           : std::numeric_limits<double>::infinity();
    if (alt_better) {
      best = std::move(alt);
      setup = other;
      if (selection) *selection = other_selection;
    }
    if (best.ok()) best.sensors[s].flip_log_likelihood_ratio = llr;
  }
  return best;
}

/// Bias orders: as given, or forward selection: from order 1 everywhere, the one sensor's next
/// order that lowers the BIC most, until none does.
RigResult fitWithOrders(const RigObservations& obs, const RigConfig& config, FitSetup setup) {
  const std::size_t S = obs.sensors.size();
  const bool choose = config.orders.empty();
  setup.orders = choose ? std::vector<int>(S, 1) : config.orders;
  std::vector<std::size_t> selection;
  RigResult best = fitWithFlips(obs, config, setup, &selection);
  if (!best.ok() || !choose) return best;
  // Every order is fitted to the readings the first fit selected: likelihoods of one data set.
  setup.selection = &selection;
  best = fitWithFlips(obs, config, setup);
  if (!best.ok()) return best;
  std::vector<std::vector<std::pair<int, double>>> tried(S);
  for (std::size_t s = 0; s < S; ++s) tried[s].push_back({setup.orders[s], best.bic});
  while (choose) {
    std::size_t pick = S;
    RigResult pick_result;
    for (std::size_t s = 0; s < S; ++s) {
      if (setup.orders[s] >= config.max_order) continue;
      FitSetup next = setup;
      ++next.orders[s];
      RigResult r = fitWithFlips(obs, config, next);
      if (!r.ok()) continue;
      tried[s].push_back({next.orders[s], r.bic});
      if (r.bic < best.bic && (pick == S || r.bic < pick_result.bic)) {
        pick = s;
        pick_result = std::move(r);
      }
    }
    if (pick == S) break;
    ++setup.orders[pick];
    best = std::move(pick_result);
  }
  for (std::size_t s = 0; s < S; ++s) best.sensors[s].order_bic = tried[s];
  return best;
}

/// The sightings of poles seen from two viewpoints (sensor and stop) or more: one seen from one
/// place only is located by its own readings exactly and tells nothing about the rest.
RigObservations withoutLonePoles(const RigObservations& obs, std::size_t* dropped) {
  std::map<int, std::set<std::pair<std::size_t, std::size_t>>> views;
  for (const RigSighting& s : obs.sightings) views[s.pole].insert({s.sensor, s.stop});
  RigObservations out = obs;
  out.sightings.clear();
  for (const RigSighting& s : obs.sightings)
    if (views[s.pole].size() >= 2) out.sightings.push_back(s);
  *dropped = 0;
  for (const auto& [id, v] : views) *dropped += v.size() < 2;
  return out;
}

/// Refuses observations with no pole seen from two places.
Status refuseWithoutPoles(const RigObservations& obs, const RigObservations& all) {
  if (obs.sightings.empty() && !all.sightings.empty())
    return Status{
        StatusCode::no_shared_landmark,
        "every pole is seen from one place only (one sensor at one stop): nothing ties the "
        "sensors' "
        "frames or shows their range errors (place poles where two sensors see them, or move the "
        "vehicle between stops)"};
  if (obs.sightings.empty()) return Status{StatusCode::no_usable_landmark, "no sensor saw a pole"};
  return Status{StatusCode::ok, ""};
}

std::vector<bool> stopsWithSightings(const RigObservations& obs) {
  std::vector<bool> seen(obs.vehicle.size(), false);
  for (const RigSighting& s : obs.sightings)
    if (s.stop < seen.size()) seen[s.stop] = true;
  return seen;
}

/// The frame of the mountings: the vehicle's when its recorded poses turn enough, else relative
/// to the reference; refused when the frame asked for is not determined by the data.
Status chooseFrame(const RigObservations& obs, const RigConfig& config, const Spread& spread,
                   FitSetup* setup) {
  const std::string& ref = obs.sensors[config.reference].name;
  const bool turned = obs.vehicle_known && spread.turn_rad >= config.min_turn_rad;
  setup->frame = config.frame == RigFrame::automatic
                     ? (turned ? RigFrame::vehicle : RigFrame::relative)
                     : config.frame;
  if (setup->frame == RigFrame::vehicle && !turned)
    return Status{
        StatusCode::not_identifiable,
        std::string(obs.vehicle_known ? "the vehicle's recorded headings span only " +
                                            fixed(rad2deg(spread.turn_rad), 1) + " deg"
                                      : "the vehicle's poses are not recorded") +
            ": a mounting's position in the vehicle frame cannot be told from the poles' positions "
            "(record the vehicle's poses (--pose tf:FRAME or odom:TOPIC) while it turns by " +
            fixed(rad2deg(config.min_turn_rad), 0) +
            " deg or more, or find the mountings relative to " + ref + " with --frame relative)"};
  if (setup->frame == RigFrame::relative &&
      !(obs.vehicle_known && spread.travel_m >= config.min_travel_m)) {
    const std::vector<std::size_t> alone = unlinkedSensors(obs, config.reference);
    if (!alone.empty())
      return Status{
          StatusCode::no_shared_landmark,
          obs.sensors[alone.front()].name + " sees no pole that " + ref +
              " (or a sensor that shares poles with it) also sees: without a vehicle that moves "
              "on recorded poses, only poles two sensors see tie their frames (place poles where "
              "both see them, or record the vehicle's poses while it drives and turns)"};
  }
  return Status{StatusCode::ok, ""};
}

/// The gauge (range scale, held stops), the motion prior and the starting flips.
void completeSetup(const RigObservations& obs, const RigConfig& config, const Spread& spread,
                   FitSetup* setup) {
  setup->scale_held = !(obs.vehicle_known && spread.travel_m >= config.min_travel_m);
  setup->motion = config.motion == MotionPrior::on ||
                  (config.motion == MotionPrior::automatic && continuousRig(obs, config));
  setup->motion = setup->motion && obs.vehicle_known;
  setup->stop_held = heldStops(obs);
  setup->flips.resize(obs.sensors.size());
  for (std::size_t s = 0; s < obs.sensors.size(); ++s)
    setup->flips[s] = obs.sensors[s].prior.flip();
}

/// Refuses a fit in which a sensor reads no shared pole or whose mounting's standard errors
/// exceed the limits; marks range models not determined (checkRangeModel).
Status checkEstimates(const RigObservations& obs, const RigConfig& config, RigResult* r) {
  for (std::size_t s = 0; s < r->sensors.size(); ++s) {
    RigSensorEstimate& e = r->sensors[s];
    if (e.residuals == 0)
      return Status{StatusCode::no_shared_landmark,
                    obs.sensors[s].name +
                        " reads no pole that is seen from another place (another sensor or "
                        "another stop): nothing ties its mounting (place poles where it and "
                        "another sensor both see them)"};
    checkRangeModel(e, obs.sensors[s].name, config);
    if (e.mounting_held) continue;
    const double se_xy =
        std::sqrt(std::max(e.mounting_covariance(0, 0), e.mounting_covariance(1, 1)));
    const double se_yaw = std::sqrt(e.mounting_covariance(2, 2));
    if (se_xy > config.max_mounting_se_m || se_yaw > config.max_mounting_se_rad)
      return Status{
          StatusCode::not_identifiable,
          "the mounting of " + obs.sensors[s].name + " is determined to " +
              fixed(se_xy * 1000.0, 0) + " mm and " + fixed(rad2deg(se_yaw), 1) +
              " deg only (standard errors): " + std::to_string(e.shared_poles) + " of its " +
              std::to_string(e.poles) +
              " poles are seen by another sensor (record more poles that two sensors see, spread "
              "around the vehicle, or drive the vehicle through a turn on recorded poses)"};
  }
  return Status{StatusCode::ok, ""};
}

/// What the user should know about the fit: poles left out, the frame, the scale, the flips.
void addNotes(const RigObservations& obs, const RigConfig& config, const Spread& spread,
              std::size_t lone, RigResult* r) {
  const std::string& ref = obs.sensors[config.reference].name;
  if (lone > 0)
    r->notes.push_back(std::to_string(lone) + (lone == 1 ? " pole was" : " poles were") +
                       " seen from one place only (one sensor at one stop) and left out: such a "
                       "pole tells nothing "
                       "about the mountings or the range models");
  if (r->frame == RigFrame::vehicle)
    r->notes.push_back("mountings in the vehicle frame: the recorded poses turn by " +
                       fixed(rad2deg(spread.turn_rad), 1) + " deg over " +
                       fixed(spread.travel_m, 2) + " m");
  else
    r->notes.push_back(
        "mountings relative to " + ref + " (held at its prior): " +
        (obs.vehicle_known
             ? "the recorded poses turn by " + fixed(rad2deg(spread.turn_rad), 1) + " deg only"
             : std::string("the vehicle's poses are not recorded")) +
        ", so a mounting's place on the vehicle cannot be told from the poles' positions; only the "
        "sensors' mountings relative to each other are determined");
  if (r->scale_free)
    r->notes.push_back(
        "a range scale common to every sensor and to the geometry is not determined without a "
        "known "
        "distance (recorded poses over at least " +
        fixed(config.min_travel_m, 1) + " m, or a tape): " + ref +
        "'s alpha_1 is held at 1 and the other sensors' scales are relative to it");
  for (std::size_t s = 0; s < r->sensors.size(); ++s)
    if (r->sensors[s].flip_log_likelihood_ratio > 0.0)
      r->notes.push_back(obs.sensors[s].name +
                         (r->sensors[s].mounting.upside_down ? " upside down" : " upright") +
                         " (log-likelihood " + fixed(r->sensors[s].flip_log_likelihood_ratio, 1) +
                         " nats above the other flip)");
}

}  // namespace

const char* toString(RigFrame f) {
  switch (f) {
    case RigFrame::automatic:
      return "automatic";
    case RigFrame::vehicle:
      return "vehicle";
    case RigFrame::relative:
      return "relative";
  }
  return "unknown";
}

void RigConfig::validate(std::size_t sensors) const {
  if (sensors == 0) throw std::invalid_argument("RigConfig: no sensor");
  if (reference >= sensors) throw std::invalid_argument("RigConfig: reference is not a sensor");
  if (!orders.empty() && orders.size() != sensors)
    throw std::invalid_argument("RigConfig: one order per sensor");
  for (int o : orders)
    if (o < 1 || o > 4) throw std::invalid_argument("RigConfig: orders must be 1..4");
  if (max_order < 1 || max_order > 4)
    throw std::invalid_argument("RigConfig: max_order must be 1..4");
  if (noise_kinds.empty()) throw std::invalid_argument("RigConfig: no noise law to try");
  for (NoiseKind k : noise_kinds)
    if (k != NoiseKind::constant && k != NoiseKind::squared)
      throw std::invalid_argument("RigConfig: noise laws are constant or squared");
  if (!(sigma_vehicle_m > 0.0) || !(sigma_vehicle_rad > 0.0))
    throw std::invalid_argument("RigConfig: vehicle sigmas must be > 0");
  if (!(lateral_fraction > 0.0 && lateral_fraction <= 1.0))
    throw std::invalid_argument("RigConfig: lateral_fraction must be in (0, 1]");
}

void checkRangeModel(RigSensorEstimate& e, const std::string& name, const RigConfig& config) {
  const double d = 0.5 * (e.d_min_m + e.d_max_m);
  const auto n = static_cast<Eigen::Index>(e.model.bias.alpha.size());
  Eigen::VectorXd g(n);
  for (Eigen::Index k = 0; k < n; ++k) g(k) = std::pow(d, static_cast<double>(k));
  e.model_se_m = std::sqrt(std::max(0.0, g.dot(e.alpha_covariance * g)));
  if (e.model_se_m > config.max_model_se_m)
    e.model_status = Status{
        StatusCode::not_identifiable,
        "the range model of " + name + " is determined to " + fixed(e.model_se_m * 1000.0, 0) +
            " mm only at " + fixed(d, 2) +
            " m (standard error): its poles are seen from too few "
            "other places (record poles that it and another sensor see at several distances, or "
            "drive the vehicle past them on recorded poses)"};
  const RelativeCorrection worst = largestRelativeCorrection(e.model.bias, e.d_min_m, e.d_max_m);
  if (e.model_status.ok() && worst.fraction > kImplausibleCorrection)
    e.model_status = Status{
        StatusCode::not_identifiable,
        "the range model of " + name + " changes readings by " + fixed(worst.mm, 0) + " mm at " +
            fixed(worst.at_m, 2) + " m (" + fixed(100.0 * worst.fraction, 0) +
            " %), more than lidars are built to: over the distances its poles were seen at (" +
            fixed(e.d_min_m, 2) + "-" + fixed(e.d_max_m, 2) +
            " m) the polynomial trades off "
            "against the mounting (record poles that it and another sensor see over a wider span "
            "of distances, 1-10 m)"};
}

RigRelativeMounting relativeMountingWithCovariance(const Mounting& a, const Mounting& b,
                                                   const Eigen::Matrix<double, 6, 6>& covariance) {
  RigRelativeMounting r;
  r.pose = relativeMounting(a, b);
  const double c = std::cos(a.yaw_rad), s = std::sin(a.yaw_rad);
  Eigen::Matrix<double, 3, 6> j = Eigen::Matrix<double, 3, 6>::Zero();
  j.row(0) << -c, -s, r.pose.y_m, c, s, 0.0;
  j.row(1) << s, -c, -r.pose.x_m, -s, c, 0.0;
  j.row(2) << 0.0, 0.0, -1.0, 0.0, 0.0, 1.0;
  r.covariance = j * covariance * j.transpose();
  return r;
}

RigResult calibrateRig(const RigObservations& all, const RigConfig& config) {
  config.validate(all.sensors.size());
  std::size_t lone = 0;
  const RigObservations obs = withoutLonePoles(all, &lone);
  RigResult fail;
  fail.reference = config.reference;
  fail.status = refuseWithoutPoles(obs, all);
  if (!fail.ok()) return fail;
  const Spread spread = recordedSpread(obs, stopsWithSightings(obs));
  FitSetup setup;
  fail.status = chooseFrame(obs, config, spread, &setup);
  if (!fail.ok()) return fail;
  completeSetup(obs, config, spread, &setup);

  RigResult r = fitWithOrders(obs, config, setup);
  if (!r.ok()) return r;
  r.status = checkEstimates(obs, config, &r);
  if (!r.ok()) return r;
  addNotes(obs, config, spread, lone, &r);
  return r;
}

}  // namespace lidarcal::calibration
