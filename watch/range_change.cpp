// SPDX-License-Identifier: BSD-3-Clause
#include "watch/range_change.hpp"

#include <cmath>
#include <stdexcept>

namespace lidarcal::watch {

void applyChange(const RangeChange& change, std::size_t index, io::RawScan& scan) {
  if (change.none() || index < change.from_scan) return;
  for (float& r : scan.ranges_m)
    if (std::isfinite(r) && r > 0.0f)
      r = static_cast<float>((1.0 + change.scale) * r + change.offset_m);
}

namespace {

double number(const std::string& text, const std::string& whole) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v))
    throw std::invalid_argument("'" + whole + "': '" + text + "' is not a number");
  return v;
}

}  // namespace

RangeChange parseRangeChange(const std::string& text) {
  const std::size_t at = text.find('@');
  if (at == std::string::npos || at == 0 || at + 1 == text.size())
    throw std::invalid_argument("'" + text +
                                "': expected OFFSET_MM@SCAN, SCALE%@SCAN or OFFSET_MM+SCALE%@SCAN "
                                "(e.g. 20@300, 0.3%@300)");
  RangeChange c;
  const double first = number(text.substr(at + 1), text);
  if (first < 0.0 || first != std::floor(first))
    throw std::invalid_argument("'" + text + "': the scan must be a whole number >= 0");
  c.from_scan = static_cast<std::size_t>(first);
  std::string terms = text.substr(0, at);
  std::size_t start = 0;
  while (start <= terms.size()) {
    const std::size_t plus = terms.find('+', start == 0 ? 1 : start);
    std::string term =
        terms.substr(start, plus == std::string::npos ? std::string::npos : plus - start);
    if (term.empty()) throw std::invalid_argument("'" + text + "': an empty term");
    if (term.back() == '%')
      c.scale += number(term.substr(0, term.size() - 1), text) / 100.0;
    else
      c.offset_m += number(term, text) / 1000.0;
    if (plus == std::string::npos) break;
    start = plus + 1;
  }
  return c;
}

}  // namespace lidarcal::watch
