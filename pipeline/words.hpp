#pragma once
// Small helpers for printed text.

#include <cstddef>
#include <string>
#include <utility>

#include "pipeline/papers.hpp"

namespace lidarcal::pipeline {

/// "1 stop", "2 stops", "0 stops" (`plural_word` for irregular plurals).
inline std::string plural(std::size_t n, const std::string& word, const std::string& plural_word = "") {
  return std::to_string(n) + " " + (n == 1 ? word : (plural_word.empty() ? word + "s" : plural_word));
}

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
