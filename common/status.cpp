// SPDX-License-Identifier: BSD-3-Clause
#include "common/status.hpp"

#include <array>
#include <utility>

namespace lidarcal {
namespace {

constexpr std::array<std::pair<StatusCode, const char*>, 26> kNames = {{
    {StatusCode::ok, "ok"},
    {StatusCode::too_few_stops, "too_few_stops"},
    {StatusCode::no_baseline, "no_baseline"},
    {StatusCode::no_usable_landmark, "no_usable_landmark"},
    {StatusCode::too_few_observations, "too_few_observations"},
    {StatusCode::joint_failed, "joint_failed"},
    {StatusCode::no_radius, "no_radius"},
    {StatusCode::too_few_reference_stops, "too_few_reference_stops"},
    {StatusCode::no_invertible_order, "no_invertible_order"},
    {StatusCode::no_intensity, "no_intensity"},
    {StatusCode::exception, "exception"},
    {StatusCode::not_run, "not_run"},
    {StatusCode::too_few_readings, "too_few_readings"},
    {StatusCode::no_readings, "no_readings"},
    {StatusCode::solver_failed, "solver_failed"},
    {StatusCode::baseline_failed, "baseline_failed"},
    {StatusCode::calibration_failed, "calibration_failed"},
    {StatusCode::cross_validation_failed, "cross_validation_failed"},
    {StatusCode::too_few_scans, "too_few_scans"},
    {StatusCode::too_few_beams, "too_few_beams"},
    {StatusCode::too_few_walls, "too_few_walls"},
    {StatusCode::not_identifiable, "not_identifiable"},
    {StatusCode::no_shared_landmark, "no_shared_landmark"},
    {StatusCode::too_few_samples, "too_few_samples"},
    {StatusCode::degenerate_motion, "degenerate_motion"},
    {StatusCode::negative_axle, "negative_axle"},
}};

}  // namespace

const char* toString(StatusCode code) {
  for (const auto& [c, name] : kNames)
    if (c == code) return name;
  return "unknown";
}

std::optional<StatusCode> parseStatusCode(std::string_view name) {
  for (const auto& [c, n] : kNames)
    if (name == n) return c;
  return std::nullopt;
}

}  // namespace lidarcal
