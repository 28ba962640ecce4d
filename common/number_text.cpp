// SPDX-License-Identifier: BSD-3-Clause
#include "common/number_text.hpp"

#include <cstdio>

namespace lidarcal {

std::string fixed(double v, int digits, bool sign) {
  char text[64];
  std::snprintf(text, sizeof text, sign ? "%+.*f" : "%.*f", digits, v);
  return text;
}

std::string significant(double v, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, v);
  return text;
}

}  // namespace lidarcal
