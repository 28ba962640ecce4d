// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A count with its noun ("1 stop", "2 stops") for every message a user reads: the libraries'
// statuses and the commands' output alike.

#include <cstddef>
#include <string>

namespace lidarcal {

/// "1 stop", "2 stops", "0 stops" (`plural_word` for irregular plurals: "1 entry", "2 entries").
inline std::string plural(std::size_t n, const std::string& word,
                          const std::string& plural_word = "") {
  return std::to_string(n) + " " +
         (n == 1 ? word : (plural_word.empty() ? word + "s" : plural_word));
}

}  // namespace lidarcal
