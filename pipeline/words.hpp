#pragma once
// Small helpers for printed text.

#include <cstddef>
#include <string>
#include <utility>

#include "common/plural.hpp"
#include "pipeline/papers.hpp"

namespace lidarcal::pipeline {

using lidarcal::plural;  // common/plural.hpp: "1 stop", "2 stops"

/// Library text (model fields, messages) cites the papers by their seed numbers; users know
/// them by author and year.
inline std::string userWords(std::string text) {
  const std::pair<const char*, const char*> names[] = {
      {"seed 000", papers::kLandmarks}, {"seed 004", papers::kTriangulation}, {"seed 003", papers::kNoiseConsistency}};
  for (const auto& [seed, paper] : names)
    for (std::size_t at = text.find(seed); at != std::string::npos; at = text.find(seed, at))
      text.replace(at, std::string(seed).size(), paper);
  return text;
}

}  // namespace lidarcal::pipeline
