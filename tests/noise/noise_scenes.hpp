// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Small observation scenes for the noise-estimation tests (known truth, fixed layouts).

#include <cmath>

#include "common/observation_scene.hpp"

namespace lidarcal::test {

/// A 6 m square driven `laps` times with turns, 12 landmarks around it, two sensors with the
/// given noise (reading landmarks from 1 m on) and the given process noise.
inline ObservationScene squareScene(int laps, const SensorNoise& s0, const SensorNoise& s1,
                                    const ProcessNoise& q) {
  ObservationScene scene;
  scene.name = "test square";
  RangeBearingSensor a, b;
  // a real sensor's blind zone: no readings of a pole the robot brushes
  a.min_range_m = b.min_range_m = 1.0;
  a.name = "a";
  a.noise = s0;
  b.name = "b";
  b.noise = s1;
  scene.sensors = {a, b};
  scene.process = q;
  const double xs[] = {-2.5, 1.0, 3.0, 5.0, 8.5, 8.0, 4.5, 2.0, -2.0, 8.7, -2.2, 3.1};
  const double ys[] = {-2.0, -2.5, 2.5, -2.4, -1.0, 3.0, 8.5, 8.7, 5.0, 7.5, 2.0, 4.0};
  for (int i = 0; i < 12; ++i) scene.landmarks.push_back(PointLandmark{xs[i], ys[i]});
  scene.motions = {MotionSpec{1.0, 0.0, 0.0, 5}, MotionSpec{1.0, 0.0, kPi / 2.0, 1}};
  scene.repeat = 4 * laps;
  return scene;
}

}  // namespace lidarcal::test
