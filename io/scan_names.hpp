// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Scan file names: `PREFIX<digits>.pcd`, their numbers read without copying the name, and the
// names written back. Internal to io/ (the sequence reader and its scan list).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace lidarcal::io {

/// Ends in `.pcd` (exactly: lidarcal reads only those).
bool isPcdName(std::string_view name);

/// `.PCD`, `.Pcd`, ...: a scan the user meant, with an extension lidarcal would skip.
bool isPcdNameInOtherCase(const std::string& name);

/// A scan name `PREFIX<digits>.pcd`: the digits are the scan number. No number when the stem
/// does not end in a digit or the digits follow a '.' (a decimal fraction, e.g. a time stamp).
/// Views into the name (a sequence of 100,000 names is checked without copying them).
struct ScanNumber {
  std::string_view prefix;  ///< the stem before the digits
  std::string_view value;   ///< the digits without leading zeros ("0" for zero)
};

/// The number of a `.pcd` name, if it has one.
std::optional<ScanNumber> scanNumber(std::string_view name);

/// A name PREFIX<width digits>.pcd whose number fits in 64 bits.
struct NumberedName {
  std::string_view prefix;
  std::size_t width = 0;
  std::uint64_t number = 0;
};

/// The name read as a NumberedName; none when it is not one, or its number exceeds 64 bits.
std::optional<NumberedName> numberedName(std::string_view name);

/// Appends the name PREFIX + `number` zero-padded to `width` digits + `.pcd`.
void appendNumberedName(std::string& out, std::string_view prefix, std::size_t width,
                        std::uint64_t number);

/// The name PREFIX + `number` zero-padded to `width` digits + `.pcd`.
std::string numberedFileName(std::string_view prefix, std::size_t width, std::uint64_t number);

/// Numbers (digit strings without leading zeros) compare by length, then text (no overflow
/// however long).
bool numberLess(std::string_view a, std::string_view b);

}  // namespace lidarcal::io
