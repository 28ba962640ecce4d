// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/evaluation.hpp"

#include <cmath>
#include <stdexcept>

#include <complex>

namespace lidarcal::calibration {

RangeComparison compareRanges(const std::vector<double>& truth, const std::vector<double>& raw,
                              const std::vector<double>& corrected) {
  if (truth.size() != raw.size() || truth.size() != corrected.size())
    throw std::invalid_argument("compareRanges: sizes differ");
  RangeComparison c;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (!std::isfinite(truth[i]) || !std::isfinite(raw[i]) || !std::isfinite(corrected[i]) ||
        truth[i] <= 0.0)
      continue;
    const double er = raw[i] - truth[i], ec = corrected[i] - truth[i];
    c.mse_raw_m2 += er * er;
    c.mse_corrected_m2 += ec * ec;
    c.nmse_raw += er * er / (truth[i] * truth[i]);
    c.nmse_corrected += ec * ec / (truth[i] * truth[i]);
    ++c.n;
  }
  if (c.n == 0) return c;
  const double n = static_cast<double>(c.n);
  c.mse_raw_m2 /= n;
  c.mse_corrected_m2 /= n;
  c.nmse_raw /= n;
  c.nmse_corrected /= n;
  c.mse_ratio = c.mse_corrected_m2 > 0.0 ? c.mse_raw_m2 / c.mse_corrected_m2 : 0.0;
  return c;
}

double similarityScale(const std::vector<Pose2>& from, const std::vector<Pose2>& to) {
  if (from.size() != to.size() || from.size() < 2)
    throw std::invalid_argument("similarityScale: need 2+ matching points");
  // In the plane a similarity is b = z a + t with complex z = s e^(i phi); least squares on the
  // centred points gives z = sum conj(a') b' / sum |a'|^2 (the 2D case of Umeyama 1991).
  std::complex<double> ma, mb;
  for (std::size_t i = 0; i < from.size(); ++i) {
    ma += std::complex<double>(from[i].x_m, from[i].y_m);
    mb += std::complex<double>(to[i].x_m, to[i].y_m);
  }
  ma /= static_cast<double>(from.size());
  mb /= static_cast<double>(from.size());
  std::complex<double> num;
  double den = 0.0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const auto a = std::complex<double>(from[i].x_m, from[i].y_m) - ma;
    const auto b = std::complex<double>(to[i].x_m, to[i].y_m) - mb;
    num += std::conj(a) * b;
    den += std::norm(a);
  }
  if (!(den > 0.0)) throw std::invalid_argument("similarityScale: the points coincide");
  return std::abs(num) / den;
}

}  // namespace lidarcal::calibration
