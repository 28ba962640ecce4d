// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Numbers as text for messages and reports, in the two forms the project prints.

#include <string>

namespace lidarcal {

/// `v` with `digits` decimals ("%.*f"), with a leading + for positive values when `sign`.
std::string fixed(double v, int digits, bool sign = false);

/// fixed(v, digits, sign), or "-" when `v` is not finite (a table cell with no value).
std::string fixedOrDash(double v, int digits, bool sign = false);

/// `v` with `digits` significant digits ("%.*g").
std::string significant(double v, int digits);

/// printf's text for `format` and the values, whatever its length.
[[gnu::format(printf, 1, 2)]] std::string formatted(const char* format, ...);

}  // namespace lidarcal
