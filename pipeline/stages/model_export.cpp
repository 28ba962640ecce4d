// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/model_export.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"

namespace lidarcal::pipeline {
namespace {

/// Shortest text that reads back as the same double.
std::string number(double v) {
  if (!std::isfinite(v)) return ".nan";
  char text[40];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, v);
    if (std::strtod(text, nullptr) == v) break;
  }
  return text;
}

std::string list(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + number(values[i]);
  return out + "]";
}

// a JSON string is a YAML string
std::string quoted(const std::string& s) { return nlohmann::json(s).dump(); }

}  // namespace

std::pair<double, double> correctedReadings(const CalibrationModel& model,
                                            calibration::Outside outside,
                                            const std::string& model_file) {
  const calibration::CorrectionWindow w = calibration::correctionWindow(model, outside);
  const bool beyond =
      outside == calibration::Outside::extrapolate || outside == calibration::Outside::linear;
  if (model.fitted_range_m && !beyond) return {w.reading_min_m, w.reading_max_m};
  const RangeModel& m = model.model;
  const bool limits_known = m.range_max_m < 1e9 && std::isfinite(m.range_min_m);
  // The continuation corrects every reading; without the sensor's limits the table covers the
  // fit's.
  if (!limits_known && model.fitted_range_m && outside == calibration::Outside::linear)
    return {w.reading_min_m, w.reading_max_m};
  if (!limits_known)
    throw DataError(model_file, "fitted_range / sensor.range_max_m",
                    "the model records neither the range it was fitted over nor the sensor's range "
                    "limits, so the "
                    "readings it corrects are unknown",
                    "calibrate again with this lidarcal (it records fitted_range)");
  return {m.range_min_m, m.range_max_m};
}

std::string exportYaml(const CalibrationModel& model, const ExportConfig& config) {
  // The readings the fit itself covers; with `linear` the others are continued from its edges.
  const auto [y_lo, y_hi] = correctedReadings(
      model,
      config.outside == calibration::Outside::linear ? calibration::Outside::keep : config.outside,
      config.source);
  const auto [d_lo, d_hi] = model.fitted_range_m.value_or(
      std::pair<double, double>(model.model.range_min_m, model.model.range_max_m));
  std::string y;
  y += "# lidarcal range model for a ROS driver (lidarcal export --format yaml; docs/FORMAT.md)\n";
  y += "# from " + config.source + "\n";
  y += "# A reading y (metres) in valid_reading_m is corrected to the distance d with f(d) = y,\n";
  y += "# f(d) = sum_i bias_alpha[i] * d^i; readings outside valid_reading_m: see `outside`\n";
  y += "# (linear: d = d_edge + (y - f(d_edge)) / f'(d_edge) at the nearer edge of "
       "valid_range_m).\n";
  y += "format: \"lidarcal-ros-params/1\"\n";
  y += "sensor_name: " + quoted(model.sensor_name) + "\n";
  y += "beams: " + (model.beams ? std::to_string(*model.beams) : std::string("0")) +
       "  # 0: not recorded\n";
  y += "bias_alpha: " + list(model.model.bias.alpha) + "  # alpha_i in m^(1-i)\n";
  y += "valid_range_m: " + list({d_lo, d_hi}) + "  # true distances the model was fitted over\n";
  y += "valid_reading_m: " + list({y_lo, y_hi}) + "  # readings corrected\n";
  y += "range_min_m: " + number(model.model.range_min_m) + "\n";
  y += "range_max_m: " + number(model.model.range_max_m) + "\n";
  y += "inversion: " + std::string(calibration::toString(config.inversion)) +
       "  # ls: the d with f(d) = y; ml: the most likely d (squared noise law)\n";
  y += "outside: " + std::string(calibration::toString(config.outside)) +
       "  # readings outside valid_reading_m: " + calibration::outsideNames() + "\n";
  y += "noise_law: " + std::string(toString(model.model.noise.kind)) + "\n";
  y += "noise_sigma_e: " + number(model.model.noise.sigma_e) + "\n";
  return y;
}

std::string exportLut(const CalibrationModel& model, const ExportConfig& config) {
  const auto [lo, hi] = correctedReadings(model, config.outside, config.source);
  if (!(config.step_m > 0.0) || !std::isfinite(config.step_m))
    throw InputError("", "--step", "must be a positive number of metres", "e.g. --step 0.001");
  const double rows = std::floor((hi - lo) / config.step_m) + 2.0;
  if (rows > 1e7)
    throw InputError("", "--step",
                     "gives " + number(rows) + " rows over the readings " + number(lo) + "-" +
                         number(hi) + " m (at most 10^7)",
                     "use a larger step");
  const calibration::ReadingCorrector correct =
      calibration::readingCorrector(model, config.inversion, config.outside);
  std::string out = "reading_m,range_m\n";
  out.reserve(static_cast<std::size_t>(rows) * 24);
  char text[64];
  auto row = [&](const std::string& reading_text) {
    // The row's reading is the printed value: its range is what `correct` gives for exactly it.
    const calibration::CorrectedReading c = correct(std::strtod(reading_text.c_str(), nullptr));
    out += reading_text + ',';
    if (std::isfinite(c.range_m)) {
      std::snprintf(text, sizeof text, "%.9g", c.range_m);
      out += text;
    } else {
      out += "nan";
    }
    out += '\n';
  };
  // First and last rows exactly at the window's ends; the steps between at 9 significant digits.
  row(number(lo));
  const auto steps = static_cast<std::size_t>(std::floor((hi - lo) / config.step_m));
  for (std::size_t i = 1; i <= steps; ++i) {
    const double y = lo + static_cast<double>(i) * config.step_m;
    if (!(y < hi - 1e-9 * std::max(1.0, hi))) break;
    std::snprintf(text, sizeof text, "%.9g", y);
    row(text);
  }
  if (hi > lo) row(number(hi));
  return out;
}

}  // namespace lidarcal::pipeline
