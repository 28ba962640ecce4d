// SPDX-License-Identifier: BSD-3-Clause
#include "common/effect.hpp"

namespace lidarcal {

const std::vector<EffectInfo>& effectTable() {
  // name, sequence statistic, static statistic, joint term, scene key
  static const std::vector<EffectInfo> table = {
      {Effect::incidence_noise, "incidence_noise", "spread_vs_incidence", "spread_vs_incidence",
       true, "sensor.effects.incidence_noise_exponent"},
      {Effect::incidence_bias, "incidence_bias", "residual_vs_incidence", "wall_curvature", true,
       "sensor.effects.incidence_bias_m"},
      {Effect::landmark_bias, "landmark_bias", "landmark_identity", "", true,
       "landmarks[].range_offset_m"},
      {Effect::heading_error, "heading_error", "heading_within_stop", "", true,
       "path.sigma_psi_deg"},
      {Effect::range_drift, "range_drift", "residual_vs_time", "residual_vs_time", true,
       "sensor.effects.range_drift_m_per_scan"},
      {Effect::mixed_pixels, "mixed_pixels", "edge_excess", "edge_excess", true,
       "sensor.effects.mixed_pixel_fraction"},
      {Effect::angle_offset, "angle_offset", "path_rotation", "", true, "sensor.mount_yaw_deg"},
      {Effect::range_noise_law, "range_noise_law", "spread_vs_range", "spread_vs_range", true,
       "sensor.noise.exponent"},
      {Effect::odometry_scale, "odometry_scale", "path_scale", "", true,
       "path.step_error_fraction"},
      {Effect::heavy_tails, "heavy_tails", "tail_weight", "tail_weight", true,
       "sensor.effects.noise_student_dof"},
      {Effect::quantisation, "quantisation", "quantisation_1mm", "quantisation", true,
       "sensor.effects.range_resolution_m"},
      {Effect::dark_surface, "dark_surface", "spread_vs_intensity", "spread_vs_intensity", true,
       "sensor.effects.dark_noise_exponent"},
  };
  return table;
}

const EffectInfo& info(Effect e) { return effectTable()[static_cast<std::size_t>(e)]; }

const char* toString(Effect e) { return info(e).name; }

std::optional<Effect> parseEffect(std::string_view name) {
  for (const auto& i : effectTable())
    if (name == i.name) return i.effect;
  return std::nullopt;
}

}  // namespace lidarcal
