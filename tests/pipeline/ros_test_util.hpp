// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Shared by the export, bag and node tests: a hand-made model.json (the oracle knows its
// polynomial) and a small CSV reader for the exported lookup table.

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "common/calibration_model.hpp"
#include "io/model_io.hpp"
#include "io/rig_model_io.hpp"
#include "test_util.hpp"

namespace lidarcal::test {

/// f(d) = 0.03 + 0.98 d + 0.004 d^2 (increasing), squared noise law, fitted over 0.5-8 m, range
/// window 0.15-12 m, sensor `name`, `beams` per scan (0: not recorded).
inline CalibrationModel polynomialModel(const std::string& name, int beams) {
  CalibrationModel m;
  m.method = "joint";
  m.sensor_name = name;
  if (beams > 0) m.beams = beams;
  m.model.bias.alpha = {0.03, 0.98, 0.004};
  m.model.noise.kind = NoiseKind::squared;
  m.model.noise.sigma_e = 0.002;
  m.model.range_min_m = 0.15;
  m.model.range_max_m = 12.0;
  m.fitted_range_m = std::make_pair(0.5, 8.0);
  return m;
}

/// A rig model of two 100-beam lidars, "front" on `front_topic` (polynomialModel) and "back" on
/// `back_topic` (f(d) = -0.02 + 1.01 d): each topic corrected by its own block differs from the
/// other's.
inline io::RigModel twoLidarModel(const std::string& front_topic, const std::string& back_topic) {
  io::RigModel rig;
  rig.frame = "relative";
  rig.reference = "front";
  for (const std::string name : {"front", "back"}) {
    io::RigModelSensor s;
    s.name = name;
    s.topic = name == "front" ? front_topic : back_topic;
    s.frame_id = "laser_" + name;
    s.model = polynomialModel("", 100);
    if (name == "back") s.model.model.bias.alpha = {-0.02, 1.01, 0.0};
    rig.sensors.push_back(s);
  }
  return rig;
}

/// Rows of `reading_m,range_m` (NaN for "nan"); fails the test on a malformed line.
inline std::vector<std::pair<double, double>> readLut(const std::string& text) {
  std::vector<std::pair<double, double>> rows;
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "reading_m,range_m");
  while (std::getline(in, line)) {
    const auto comma = line.find(',');
    EXPECT_NE(comma, std::string::npos) << line;
    if (comma == std::string::npos) break;
    const std::string second = line.substr(comma + 1);
    rows.emplace_back(std::strtod(line.c_str(), nullptr),
                      second == "nan" ? std::nan("") : std::strtod(second.c_str(), nullptr));
  }
  return rows;
}

}  // namespace lidarcal::test
