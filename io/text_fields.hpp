// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Splitting text records into fields and parsing numbers without copies (io-internal, used by
// the line-based importers).

#include <string_view>
#include <vector>

namespace lidarcal::io {

/// Splits at runs of spaces and tabs; `fields` is cleared first and views into `line`.
void splitWhitespace(std::string_view line, std::vector<std::string_view>& fields);

/// Splits at commas; surrounding spaces are trimmed from every field. An empty line gives no field.
void splitCommas(std::string_view line, std::vector<std::string_view>& fields);

/// Parses a whole field as a number (decimal or exponent form, optional sign, "nan", "inf").
/// Returns false when the field is empty or has anything else in it.
bool parseNumber(std::string_view field, double& value);

}  // namespace lidarcal::io
