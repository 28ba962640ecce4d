// SPDX-License-Identifier: BSD-3-Clause
#include "io/scan_names.hpp"

#include <cctype>
#include <cstdio>
#include <limits>

#include "io/sequence.hpp"

namespace lidarcal::io {

std::string scanFileName(std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "scan_%06zu.pcd", index);
  return name;
}

bool isPcdName(std::string_view name) {
  return name.size() > 4 && name.compare(name.size() - 4, 4, ".pcd") == 0;
}

bool isPcdNameInOtherCase(const std::string& name) {
  if (name.size() <= 4 || isPcdName(name)) return false;
  std::string ext = name.substr(name.size() - 4);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".pcd";
}

std::optional<ScanNumber> scanNumber(std::string_view name) {
  const std::string_view stem = name.substr(0, name.size() - 4);
  std::size_t start = stem.size();
  while (start > 0 && std::isdigit(static_cast<unsigned char>(stem[start - 1]))) --start;
  if (start == stem.size() || (start > 0 && stem[start - 1] == '.')) return std::nullopt;
  const std::string_view digits = stem.substr(start);
  const std::size_t nz = digits.find_first_not_of('0');
  return ScanNumber{stem.substr(0, start),
                    nz == std::string_view::npos ? std::string_view("0") : digits.substr(nz)};
}

std::optional<NumberedName> numberedName(std::string_view name) {
  if (!isPcdName(name)) return std::nullopt;
  const std::optional<ScanNumber> n = scanNumber(name);
  if (!n) return std::nullopt;
  NumberedName r;
  r.prefix = n->prefix;
  r.width = name.size() - 4 - n->prefix.size();
  for (char c : n->value) {
    const std::uint64_t d = static_cast<std::uint64_t>(c - '0');
    if (r.number > (std::numeric_limits<std::uint64_t>::max() - d) / 10) return std::nullopt;
    r.number = r.number * 10 + d;
  }
  return r;
}

void appendNumberedName(std::string& out, std::string_view prefix, std::size_t width,
                        std::uint64_t number) {
  char digits[24];
  std::size_t len = 0;
  do {
    digits[len++] = static_cast<char>('0' + number % 10);
    number /= 10;
  } while (number != 0);
  out += prefix;
  if (width > len) out.append(width - len, '0');
  while (len > 0) out += digits[--len];
  out += ".pcd";
}

std::string numberedFileName(std::string_view prefix, std::size_t width, std::uint64_t number) {
  std::string name;
  appendNumberedName(name, prefix, width, number);
  return name;
}

bool numberLess(std::string_view a, std::string_view b) {
  return a.size() != b.size() ? a.size() < b.size() : a < b;
}

}  // namespace lidarcal::io
