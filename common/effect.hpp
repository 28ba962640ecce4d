// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The effects beyond the seeds' range model (Alhashimi et al. 2021 A3-A4, Alhashimi et al. 2016 eq.
// 1) that the calibration can estimate, the simulator can produce and `lidarcal diagnose` looks
// for: one enum and one table with everything that names them (the name in diagnosis.json and on
// the command line, the discrepancy statistic aimed at each in both kinds of data, which data can
// test it, the scene key that simulates it). Physical causes: docs/FORMAT.md ("Effects"). Adding an
// effect: a row here, its term in RangeEffects (simulator) and JointEffects (fit), and its fit in
// the diagnosis modes that test it.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace lidarcal {

enum class Effect {
  incidence_noise,  ///< noise grows as (1 / cos phi)^gamma
  incidence_bias,   ///< reading grows by b (1 - cos phi)
  landmark_bias,    ///< a range offset per surface (reflectivity)
  heading_error,    ///< the heading at each stop differs from the commanded one
  range_drift,      ///< readings grow with time (warm-up)
  mixed_pixels,     ///< edge beams read between foreground and background
  angle_offset,     ///< the lidar is mounted rotated
  range_noise_law,  ///< noise grows as f(d)^kappa, kappa not 2
  odometry_scale,   ///< steps differ from the commanded length by a fraction
  heavy_tails,      ///< Student-t noise (a symptom: static data)
  quantisation,     ///< readings on a grid (the sensor's range resolution)
  /// dark surfaces return wide errors: noise grows as (I_ref / I)^delta (data with intensity)
  dark_surface,
};

/// What names an effect, and where each kind of data tests it.
struct EffectInfo {
  Effect effect;
  const char* name;  ///< in diagnosis.json, `diagnose --candidates`, `calibrate --effects`
  /// The battery's score statistic aimed at it in a sequence; nullptr: not a sequence candidate.
  const char* sequence_statistic;
  /// Its statistic in static data ("" when the battery has none for it); nullptr: not a static
  /// candidate.
  const char* static_statistic;
  bool joint_term;        ///< the joint refinement has a term for it (`calibrate --effects`)
  const char* scene_key;  ///< scene key that simulates it ("" when it is a model or path setting)
};

/// Every effect, in the order of the enum (the order candidates are listed and reported in).
const std::vector<EffectInfo>& effectTable();
const EffectInfo& info(Effect e);
const char* toString(Effect e);
/// The effect of that name; nullopt for any other string.
std::optional<Effect> parseEffect(std::string_view name);
/// Names of the effects for which `keep` holds, joined by ", " (for error messages).
template <class Pred>
std::string effectNames(Pred keep) {
  std::string s;
  for (const auto& i : effectTable())
    if (keep(i)) s += (s.empty() ? "" : ", ") + std::string(i.name);
  return s;
}

}  // namespace lidarcal
