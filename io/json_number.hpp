// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Numbers in the JSON files lidarcal writes: JSON has no NaN or infinity, so a number that is not
// finite is written as null (docs/FORMAT.md).

#include <cmath>

#include <nlohmann/json.hpp>

namespace lidarcal::io {

/// `v`, or null when it is not finite.
template <class Json = nlohmann::ordered_json>
Json jsonNumber(double v) {
  return std::isfinite(v) ? Json(v) : Json(nullptr);
}

}  // namespace lidarcal::io
