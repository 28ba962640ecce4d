#pragma once
// Small numeric helpers shared across the libraries: the non-finite constants, ln(2 pi), the
// medians and a one-dimensional maximiser. One definition each (issue 18 found them copied a
// dozen times).

#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace lidarcal {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();  ///< "no value"
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kLog2Pi = 1.8378770664093453;  ///< ln(2 pi), the Gaussian log-density's constant

/// Median: the middle value, or the mean of the two middle values for an even count; NaN when empty.
inline double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

/// Upper median: the value at position n / 2 of the sorted values (the median for an odd count,
/// the upper of the two middle values for an even one; no averaging); NaN when empty.
inline double upperMedian(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

/// Maximum of a unimodal function on [lo, hi] by ternary search: `iterations` times the third
/// on the lower side of the two inner points is dropped; returns the middle of what is left.
template <class Fn>
double ternaryMax(Fn fn, double lo, double hi, int iterations) {
  for (int i = 0; i < iterations; ++i) {
    const double m1 = lo + (hi - lo) / 3.0, m2 = hi - (hi - lo) / 3.0;
    if (fn(m1) < fn(m2)) lo = m1;
    else hi = m2;
  }
  return 0.5 * (lo + hi);
}

}  // namespace lidarcal
