// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// JSON files of noise estimation (docs/FORMAT.md): observation scenes (`"kind": "observations"`),
// noise_truth.json (simulator output), and noise settings (`--init` of noise-consistency and the
// `sensors` / `process_var` part of its result.json).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "common/observation.hpp"
#include "common/observation_scene.hpp"

namespace lidarcal::io {

/// The `kind` of a scene file: "scans" (the default when absent) or "observations". Throws
/// InputError for any other value or for a file that is not a JSON object.
std::string readSceneKind(const std::filesystem::path& file);

/// Reads and validates an observation scene. Throws InputError naming the file and field.
ObservationScene readObservationScene(const std::filesystem::path& file);
/// An observation scene as JSON (the schema readObservationScene accepts).
nlohmann::ordered_json observationSceneToJson(const ObservationScene& scene);

/// A noise setting as JSON: {"sensors": [{sensor, range_mean_m, range_var_m2, bearing_mean_rad,
/// bearing_var_rad2}], "process_var": {dx_m2, dy_m2, dtheta_rad2}}.
nlohmann::ordered_json noiseSettingToJson(const NoiseSetting& setting);
/// Reads a noise setting from a JSON file with that schema (other keys are ignored, so a
/// result.json or noise_truth.json can be read as a setting). Entry i is sensor i, or with
/// `sensor_labels` the sensor labelled (*sensor_labels)[i] (observations.csv's ids). Throws
/// InputError.
NoiseSetting readNoiseSetting(const std::filesystem::path& file,
                              const std::vector<int>* sensor_labels = nullptr);

/// Truth of an observation simulation.
struct NoiseTruth {
  std::uint64_t seed = 0;    ///< simulator seed
  ObservationScene scene;    ///< the scene simulated (true noise inside)
  std::vector<Pose2> poses;  ///< true pose of every stop
};
/// Writes noise_truth.json atomically.
void writeNoiseTruth(const std::filesystem::path& file, const NoiseTruth& truth);
/// Reads noise_truth.json. Throws InputError.
NoiseTruth readNoiseTruth(const std::filesystem::path& file);

}  // namespace lidarcal::io
