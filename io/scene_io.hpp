// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Scene files (input of `lidarcal simulate`) and truth files (its output), JSON.
// Formats: docs/FORMAT.md.

#include <filesystem>

#include <nlohmann/json_fwd.hpp>

#include "common/scene.hpp"
#include "common/truth.hpp"

namespace lidarcal::io {

/// Reads and validates a scene file. Throws InputError naming the file and field.
Scene readScene(const std::filesystem::path& file);
/// A scene as JSON (the same schema readScene accepts).
nlohmann::ordered_json sceneToJson(const Scene& scene);

/// Writes truth.json atomically.
void writeTruth(const std::filesystem::path& file, const Truth& truth);
/// Reads truth.json. Throws InputError on malformed content.
Truth readTruth(const std::filesystem::path& file);

}  // namespace lidarcal::io
