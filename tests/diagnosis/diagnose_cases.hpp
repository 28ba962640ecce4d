// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Simulated sequences with one effect hidden in them (or none), for the diagnosis tests and
// bench/diagnose_accuracy. The paper field of Alhashimi et al. 2021 section 4.3 at the landmark
// level: five poles of 0.12 m (radius published), ten stops of 0.30 m, ten scans per stop,
// Alhashimi et al. 2016's bias and squared noise (2 cm at 3 m), stop positions scattered by 2 cm,
// sighting bearings by 0.2 degree, and the room's walls behind the poles (the background of mixed
// pixels). Which size (and sign) the effect takes is drawn from the case seed; the tests only look
// at the name. And the static cases: a room seen from one pose (or a sensor turning in place), one
// effect each, with the causes the truth allows.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>

#include <limits>
#include <vector>

#include "common/number_text.hpp"
#include "common/rng.hpp"
#include "diagnosis/static_scene.hpp"
#include "simulation/landmark_level.hpp"
#include "simulation/simulator.hpp"

namespace lidarcal::test {

struct HiddenEffectCase {
  simulation::LandmarkLevelConfig config;  ///< the scene with the effect
  std::uint64_t seed = 0;                  ///< simulator seed
  std::string size;                        ///< the drawn size in words (messages only)
};

inline simulation::LandmarkLevelConfig paperFieldLandmarkLevel() {
  simulation::LandmarkLevelConfig c;
  c.landmarks = {
      {1.5, 0.75, 0.12}, {0.3, 2.2, 0.12}, {2.4, 3.4, 0.12}, {3.9, -1.3, 0.12}, {0.9, -2.8, 0.12}};
  c.walls = {{-1.5, -3.8, 5.0, -3.8},
             {5.0, -3.8, 5.0, 4.5},
             {5.0, 4.5, -1.5, 4.5},
             {-1.5, 4.5, -1.5, -3.8}};
  c.path.stops = 10;
  c.path.step_m = 0.30;
  c.path.scans_per_stop = 10;
  c.path.sigma_s_m = 0.02;
  c.path.sigma_psi_rad = 0.0;  // the seeds' model: no heading error shared by a stop
  c.model.bias.alpha = {0.0525, 0.8838, 0.0584};
  c.model.noise.kind = NoiseKind::squared;
  c.model.noise.sigma_e = 0.0019176;
  c.model.range_min_m = 0.2;
  c.model.range_max_m = 6.0;
  c.sigma_theta_rad = deg2rad(0.2);
  c.beams = true;
  return c;
}

/// Gives every landmark of `c` a return intensity, drawn for case `case_seed` from a stream of
/// its own (the effect's size and the simulation draw nothing else differently): log-uniform in
/// 15-250, the spread between a black and a white surface (about 5 % and 80 % reflectance).
inline void giveIntensities(simulation::LandmarkLevelConfig& c, std::uint64_t case_seed) {
  auto rng = makeRng(case_seed, 92);
  std::uniform_real_distribution<double> u(std::log(15.0), std::log(250.0));
  for (auto& l : c.landmarks) l.intensity = std::exp(u(rng));
}

/// Per-landmark offsets with sigma 2-2.5 cm: a random pattern scaled to that RMS about its mean
/// (the mean is a common offset, which the bias polynomial's alpha_0 takes).
inline std::string hideLandmarkBias(simulation::LandmarkLevelConfig& c, std::mt19937_64& rng,
                                    std::uniform_real_distribution<double>& u) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double sigma = 0.02 + 0.005 * u(rng);
  double mean = 0.0, ss = 0.0;
  for (auto& l : c.landmarks) {
    l.range_offset_m = n(rng);
    mean += l.range_offset_m / static_cast<double>(c.landmarks.size());
  }
  for (const auto& l : c.landmarks) ss += (l.range_offset_m - mean) * (l.range_offset_m - mean);
  const double rms = std::sqrt(ss / static_cast<double>(c.landmarks.size()));
  const double common = 0.02 * (u(rng) - 0.5);  // and a common part, up to +-1 cm
  for (auto& l : c.landmarks) l.range_offset_m = common + (l.range_offset_m - mean) * sigma / rms;
  return formatted("offsets %.3f %.3f %.3f %.3f %.3f m", c.landmarks[0].range_offset_m,
                   c.landmarks[1].range_offset_m, c.landmarks[2].range_offset_m,
                   c.landmarks[3].range_offset_m, c.landmarks[4].range_offset_m);
}

/// Noise growing as (I_ref / I)^delta on the landmarks' intensities (giveIntensities): delta 0.5
/// is a photon-limited spot (sigma ~ 1 / sqrt(signal)). The reference is the geometric middle of
/// the intensities' range, so the squared law's 2 cm at 3 m holds there.
inline std::string hideDarkSurface(simulation::LandmarkLevelConfig& c, std::uint64_t case_seed,
                                   std::mt19937_64& rng,
                                   std::uniform_real_distribution<double>& u) {
  giveIntensities(c, case_seed);
  c.effects.dark_noise_exponent = 0.5 + 0.5 * u(rng);  // delta in [0.5, 1]
  c.effects.dark_reference_intensity = std::sqrt(15.0 * 250.0);
  return formatted("delta %.2f, intensities %.0f %.0f %.0f %.0f %.0f",
                   c.effects.dark_noise_exponent, c.landmarks[0].intensity,
                   c.landmarks[1].intensity, c.landmarks[2].intensity, c.landmarks[3].intensity,
                   c.landmarks[4].intensity);
}

/// The case `case_seed` of effect `effect` ("none" for clean data). Sizes: around the issue's
/// "realistic" examples, drawn uniformly in the ranges below.
inline HiddenEffectCase hiddenEffectCase(const std::string& effect, std::uint64_t case_seed) {
  HiddenEffectCase h;
  h.config = paperFieldLandmarkLevel();
  h.seed = deriveSeed(case_seed, 77);
  auto rng = makeRng(case_seed, 91);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double sign = u(rng) < 0.5 ? -1.0 : 1.0;
  auto& c = h.config;
  const double scans = static_cast<double>(c.path.stops * c.path.scans_per_stop);
  if (effect == "none") {
    h.size = "clean";
  } else if (effect == "incidence_noise") {
    // sigma (1 / cos phi)^gamma, gamma in [1, 1.5]
    c.effects.incidence_noise_exponent = 1.0 + 0.5 * u(rng);
    h.size = formatted("gamma %.2f", c.effects.incidence_noise_exponent);
  } else if (effect == "incidence_bias") {
    c.effects.incidence_bias_m = sign * (0.02 + 0.02 * u(rng));  // 2-4 cm at grazing incidence
    h.size = formatted("b %.3f m", c.effects.incidence_bias_m);
  } else if (effect == "landmark_bias") {
    h.size = hideLandmarkBias(c, rng, u);
  } else if (effect == "heading_error") {
    c.path.sigma_psi_rad = deg2rad(1.0 + 0.5 * u(rng));  // per stop, 1-1.5 degrees
    h.size = formatted("sigma_psi %.2f deg", rad2deg(c.path.sigma_psi_rad));
  } else if (effect == "range_drift") {
    const double total = sign * (0.03 + 0.01 * u(rng));  // 3-4 cm over the sequence
    c.effects.range_drift_m_per_scan = total / (scans - 1.0);
    h.size = formatted("%.3f m over the sequence", total);
  } else if (effect == "mixed_pixels") {
    c.effects.mixed_pixel_fraction = 0.05 + 0.05 * u(rng);  // 5-10 % of the outermost beams
    h.size = formatted("fraction %.3f", c.effects.mixed_pixel_fraction);
  } else if (effect == "angle_offset") {
    c.mount_yaw_rad = sign * deg2rad(2.0 + u(rng));  // 2-3 degrees
    h.size = formatted("%.2f deg", rad2deg(c.mount_yaw_rad));
  } else if (effect == "range_noise_law") {
    // sigma = sigma_e f^k with k far from 2, the same noise at 3 m.
    const double k = u(rng) < 0.5 ? 0.5 + 0.5 * u(rng) : 3.0 + 0.5 * u(rng);
    const double at3 = c.model.noise.stddev(3.0, c.model.bias);
    c.model.noise.kind = NoiseKind::power;
    c.model.noise.exponent = k;
    c.model.noise.sigma_e = at3 / std::pow(c.model.bias(3.0), k);
    h.size = formatted("exponent %.2f", k);
  } else if (effect == "odometry_scale") {
    c.path.step_error_fraction = sign * (0.03 + 0.02 * u(rng));  // true steps 3-5 % off
    h.size = formatted("step error %.3f", c.path.step_error_fraction);
  } else if (effect == "heavy_tails") {
    // Student t noise, 3-5 degrees of freedom (same variance)
    c.effects.noise_student_dof = 3.0 + 2.0 * u(rng);
    h.size = formatted("nu %.2f", c.effects.noise_student_dof);
  } else if (effect == "quantisation") {
    // Readings rounded to 5, 10 or 20 mm (a sensor reporting whole centimetres: the SICK LMS
    // logs of CARMEN). The noise is 2 mm at 1 m and 2 cm at 3 m: the grid shows near the poles.
    const double grids[] = {0.005, 0.01, 0.02};
    c.effects.range_resolution_m = grids[std::min(2, static_cast<int>(3.0 * u(rng)))];
    h.size = formatted("grid %.0f mm", 1000.0 * c.effects.range_resolution_m);
  } else if (effect == "dark_surface") {
    h.size = hideDarkSurface(c, case_seed, rng, u);
  } else {
    throw std::invalid_argument("hiddenEffectCase: unknown effect " + effect);
  }
  return h;
}

inline NoiseModel squaredNoise(double sigma_e) {
  NoiseModel n;
  n.kind = NoiseKind::squared;
  n.sigma_e = sigma_e;
  return n;
}

/// The scene of staticRoom(): an irregular room seen from one pose, walls at several distances
/// and incidences, a pillar and a box (depth discontinuities), bias 0.01 + d.
inline Scene staticRoomScene(const RangeEffects& fx, const NoiseModel& noise, int scans,
                             double step_error_fraction) {
  Scene s;
  s.sensor.beams = 360;
  s.sensor.range.range_min_m = 0.15;
  s.sensor.range.range_max_m = 12.0;
  s.sensor.range.bias.alpha = {0.01, 1.0};
  s.sensor.range.noise = noise;
  s.sensor.effects = fx;
  s.path.stops = 1;
  s.path.scans_per_stop = scans;
  s.path.start = Pose2{0.3, -0.2, 0.4};
  s.path.step_error_fraction = step_error_fraction;
  s.walls = {{-2.0, -3.0, 4.0, -3.0},
             {4.0, -3.0, 4.0, 1.0},
             {4.0, 1.0, 2.5, 3.5},
             {2.5, 3.5, -2.0, 3.5},
             {-2.0, 3.5, -2.0, -3.0}};
  s.clutter = {{1.5, 1.0, 0.2}};
  s.walls.push_back({-1.0, 0.8, -0.4, 1.6});
  return s;
}

/// The empty data of `scans` scans of 360 beams from the room's lidar (0.15-12 m).
inline diagnosis::StaticScans roomScans(int scans) {
  diagnosis::StaticScans out;
  out.scans = static_cast<std::size_t>(scans);
  out.beams_per_scan = 360;
  out.range_min_m = 0.15;
  out.range_max_m = 12.0;
  return out;
}

/// The scans of a one-stop scene `s` (its scans_per_stop), as `diagnose` reads them.
/// `turn_rad_per_scan`: the sensor turns in place by this much per scan (the scans are cast from
/// the turned heading).
inline diagnosis::StaticScans sceneScans(const Scene& s, std::uint64_t seed,
                                         double turn_rad_per_scan = 0.0) {
  const auto stops = simulation::planStops(s, seed);
  diagnosis::StaticScans out = roomScans(s.path.scans_per_stop);
  out.beams_per_scan = static_cast<std::size_t>(s.sensor.beams);
  out.range_min_m = s.sensor.range.range_min_m;
  out.range_max_m = s.sensor.range.range_max_m;
  for (std::size_t k = 0; k < out.scans; ++k) {
    TruthStop stop = stops[0];
    stop.actual.yaw_rad += turn_rad_per_scan * static_cast<double>(k);
    const auto sim = simulation::simulateScan(s, stop, k, seed);
    out.has_intensity = sim.scan.has_intensity;
    for (const auto& p : *sim.scan.cloud)
      if (std::isfinite(p.x))
        out.readings.push_back(
            {std::atan2(static_cast<double>(p.y), static_cast<double>(p.x)),
             std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)),
             static_cast<std::uint32_t>(k),
             sim.scan.has_intensity ? static_cast<double>(p.intensity) : std::nan("")});
  }
  return out;
}

/// A simulated room seen from one pose (staticRoomScene), `scans` scans.
inline diagnosis::StaticScans staticRoom(const RangeEffects& fx, const NoiseModel& noise,
                                         std::uint64_t seed, int scans = 150,
                                         double step_error_fraction = 0.0,
                                         double turn_rad_per_scan = 0.0) {
  return sceneScans(staticRoomScene(fx, noise, scans, step_error_fraction), seed,
                    turn_rad_per_scan);
}

/// Where the extra-wide errors of staticRoomWithTails() occur.
enum class TailWhere { grazing, edge, dark, everywhere };

/// Which beams are of class `where`, from the truth of a scan: grazing, a true incidence above
/// 45 degrees; edge, a neighbouring beam's true distance more than 10 cm away (or no return);
/// dark, the beams on the room's fourth wall (the one 3.7 m ahead, seen at 0-32 degrees).
inline std::vector<bool> tailBeams(const simulation::SimulatedScan& sim, TailWhere where) {
  const std::size_t n = sim.truth.size();
  std::vector<bool> in(n, false);
  for (std::size_t b = 0; b < n; ++b) {
    const io::TrueRange& t = sim.truth[b];
    if (!std::isfinite(t.range_m)) continue;
    const double prev = sim.truth[(b + n - 1) % n].range_m, next = sim.truth[(b + 1) % n].range_m;
    const bool edge = !(std::abs(prev - t.range_m) <= 0.1) || !(std::abs(next - t.range_m) <= 0.1);
    const bool dark = t.target == io::TargetKind::wall && t.target_id == 4;
    in[b] = where == TailWhere::everywhere ||
            (where == TailWhere::grazing && t.incidence_rad > deg2rad(45.0)) ||
            (where == TailWhere::edge && edge) || (where == TailWhere::dark && dark);
  }
  return in;
}

/// staticRoom() with extra-wide errors the test controls: with probability `rate` a reading of a
/// beam of class `where` gets a further N(0, wide_m^2) (its own stream, drawn for every beam).
/// Every reading carries an intensity: 20 on the dark wall, 200 elsewhere (whatever `where` is).
inline diagnosis::StaticScans staticRoomWithTails(TailWhere where, double rate, double wide_m,
                                                  std::uint64_t seed, const RangeEffects& fx = {},
                                                  int scans = 150) {
  const Scene s = staticRoomScene(fx, squaredNoise(0.0015), scans, 0.0);
  const auto stops = simulation::planStops(s, seed);
  diagnosis::StaticScans out = roomScans(scans);
  out.has_intensity = true;
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (std::size_t k = 0; k < out.scans; ++k) {
    const auto sim = simulation::simulateScan(s, stops[0], k, seed);
    const std::vector<bool> in = tailBeams(sim, where), dark = tailBeams(sim, TailWhere::dark);
    auto gen = makeRng(seed, 0x7A115ULL + k);
    for (std::size_t b = 0; b < sim.truth.size(); ++b) {
      const double u = unit(gen), e = normal(gen);
      const auto& p = (*sim.scan.cloud)[b];
      if (!std::isfinite(p.x)) continue;
      const double r = std::hypot(static_cast<double>(p.x), static_cast<double>(p.y));
      out.readings.push_back({std::atan2(static_cast<double>(p.y), static_cast<double>(p.x)),
                              in[b] && u < rate ? r + wide_m * e : r, static_cast<std::uint32_t>(k),
                              dark[b] ? 20.0 : 200.0});
    }
  }
  return out;
}

/// The class of beams holding the most posterior tail readings ("" when none was counted).
inline std::string dominantTailClass(const diagnosis::TailAttribution& tails) {
  std::string top;
  double most = -1.0;
  for (const auto& [cls, n] : tails.tail_readings_by_class)
    if (n > most) {
      most = n;
      top = cls;
    }
  return top;
}

/// One static case: an effect hidden in the room and the causes the truth allows.
struct StaticCase {
  const char* name;               ///< case name
  const char* effect;             ///< the cause the truth allows (the hidden effect, or "none")
  std::vector<std::string> also;  ///< other causes the truth allows (none: only `effect`)
  RangeEffects fx;
  NoiseModel noise = squaredNoise(0.0015);
  /// alpha_0 given to the diagnosis as a reference distance would give it (NaN: not given).
  double known_offset_m = std::numeric_limits<double>::quiet_NaN();
  double step_error_fraction = 0.0;  ///< odometry scale error of the (one-stop) path
  /// Intensity each surface returns: the six walls, then the pillar (empty: none recorded).
  std::vector<double> intensities = {};
  /// Whether the truth allows `cause` to be named.
  bool allows(const std::string& cause) const {
    return cause == effect || std::find(also.begin(), also.end(), cause) != also.end();
  }
};

/// The room of case `c` seen from one pose (150 scans), the noise drawn from `seed`.
inline diagnosis::StaticScans staticRoom(const StaticCase& c, std::uint64_t seed) {
  Scene s = staticRoomScene(c.fx, c.noise, 150, c.step_error_fraction);
  for (std::size_t k = 0; k < c.intensities.size(); ++k)
    (k < s.walls.size() ? s.walls[k].intensity : s.clutter[k - s.walls.size()].intensity) =
        c.intensities[k];
  return sceneScans(s, seed);
}

/// Surfaces of several intensities (dark 20-40, bright 150-250; the median wall 90).
inline std::vector<double> roomIntensities() {
  return {200.0, 35.0, 120.0, 20.0, 90.0, 250.0, 60.0};
}

/// The static cases. The room's alpha_0 is 0.01 m. An incidence-dependent bias bends straight walls
/// almost as an offset does: with the offset given (a reference distance) it is named; without it
/// the truth allows it, "not identifiable" or nothing named (over seeds 101-110 it was named in 5
/// of 10), but no other cause. A step-length error
/// cannot exist with one pose (nothing moves): the data are clean. Quantisation: a 2 mm grid, as
/// coarse as the noise at 1-2 m (docs/results/static-diagnosis.md gives the rates for coarser
/// grids).
inline std::vector<StaticCase> staticCases() {
  auto fx = [](auto set) {
    RangeEffects e;
    set(e);
    return e;
  };
  NoiseModel half_power;  // sigma = sigma_e f^0.5, the same noise at 3 m
  half_power.kind = NoiseKind::power;
  half_power.exponent = 0.5;
  half_power.sigma_e = 0.0015 * std::pow(3.0, 1.5);
  const double none = std::numeric_limits<double>::quiet_NaN();
  return {
      {"incidence_noise", "incidence_noise", {}, fx([](RangeEffects& e) {
         e.incidence_noise_exponent = 1.0;
       })},
      {"range_drift", "range_drift", {}, fx([](RangeEffects& e) {
         e.range_drift_m_per_scan = 2e-4;
       })},
      {"heavy_tails", "heavy_tails", {}, fx([](RangeEffects& e) { e.noise_student_dof = 3.0; })},
      {"range_noise_law", "range_noise_law", {}, RangeEffects{}, half_power},
      {"incidence_bias_offset_given",
       "incidence_bias",
       {},
       fx([](RangeEffects& e) { e.incidence_bias_m = 0.05; }),
       squaredNoise(0.0015),
       0.01},
      {"incidence_bias_offset_unknown",
       "incidence_bias",
       {"not_identifiable", "none"},
       fx([](RangeEffects& e) { e.incidence_bias_m = 0.05; })},
      {"mixed_pixels", "mixed_pixels", {}, fx([](RangeEffects& e) {
         e.mixed_pixel_fraction = 0.08;
       })},
      {"quantisation", "quantisation", {}, fx([](RangeEffects& e) {
         e.range_resolution_m = 0.002;
       })},
      {"odometry_scale_cannot_exist", "none", {}, RangeEffects{}, squaredNoise(0.0015), none, 0.04},
      {"clean_with_intensities",
       "none",
       {},
       RangeEffects{},
       squaredNoise(0.0015),
       none,
       0.0,
       roomIntensities()},
      {"dark_surface",
       "dark_surface",
       {},
       fx([](RangeEffects& e) {
         e.dark_noise_exponent = 0.75;
         e.dark_reference_intensity = 90.0;
       }),
       squaredNoise(0.0015),
       none,
       0.0,
       roomIntensities()},
  };
}

}  // namespace lidarcal::test
