// SPDX-License-Identifier: BSD-3-Clause
#include "common/number_text.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace lidarcal {

std::string fixed(double v, int digits, bool sign) {
  char text[64];
  std::snprintf(text, sizeof text, sign ? "%+.*f" : "%.*f", digits, v);
  return text;
}

std::string fixedOrDash(double v, int digits, bool sign) {
  return std::isfinite(v) ? fixed(v, digits, sign) : std::string("-");
}

std::string significant(double v, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, v);
  return text;
}

std::string formatted(const char* format, ...) {
  va_list args, measure;
  va_start(args, format);
  va_copy(measure, args);
  const int n = std::vsnprintf(nullptr, 0, format, measure);
  va_end(measure);
  std::string text(n > 0 ? static_cast<std::size_t>(n) : 0, '\0');
  if (n > 0) std::vsnprintf(text.data(), text.size() + 1, format, args);
  va_end(args);
  return text;
}

}  // namespace lidarcal
