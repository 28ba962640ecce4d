// SPDX-License-Identifier: BSD-3-Clause
#include "simulation/truth_model.hpp"

#include "simulation/simulator.hpp"

namespace lidarcal::simulation {

CalibrationModel truthModel(const Scene& scene) {
  CalibrationModel m;
  m.method = "truth";
  m.model = scene.sensor.range;
  const std::size_t n = m.model.bias.alpha.size();
  m.alpha_covariance.assign(n * n, 0.0);
  m.fitted_range_m = poleDistanceRange(scene, planStops(scene, 1));
  m.status = {StatusCode::ok, ""};
  return m;
}

}  // namespace lidarcal::simulation
