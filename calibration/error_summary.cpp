// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/error_summary.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/stats_util.hpp"
#include "common/student_t.hpp"

namespace lidarcal::calibration {
namespace {

double mean(const std::vector<double>& a) {
  double s = 0.0;
  for (double v : a) s += v;
  return s / static_cast<double>(a.size());
}

/// The covariance of the means of a and b: their sample covariance (over n - 1) over n.
double covarianceOfMeans(const std::vector<double>& a, const std::vector<double>& b) {
  const double ma = mean(a), mb = mean(b), n = static_cast<double>(a.size());
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) s += (a[i] - ma) * (b[i] - mb);
  return s / (n - 1.0) / n;
}

std::vector<double> squares(const std::vector<double>& e) {
  std::vector<double> out;
  out.reserve(e.size());
  for (double v : e) out.push_back(v * v);
  return out;
}

}  // namespace

RmsError rmsError(const std::vector<double>& errors_m) {
  RmsError out;
  out.entries = errors_m.size();
  if (errors_m.empty()) return {kNaN, kNaN, 0};
  const std::vector<double> sq = squares(errors_m);
  out.rms_m = std::sqrt(mean(sq));
  out.se_m = errors_m.size() < 2 ? kNaN
             : out.rms_m > 0.0   ? std::sqrt(covarianceOfMeans(sq, sq)) / (2.0 * out.rms_m)
                                 : 0.0;
  return out;
}

MseRatio mseRatio(const std::vector<double>& raw_errors_m,
                  const std::vector<double>& corrected_errors_m, double level) {
  if (raw_errors_m.size() != corrected_errors_m.size())
    throw std::invalid_argument("mseRatio: raw and corrected errors differ in number");
  MseRatio out;
  out.level = level;
  out.entries = raw_errors_m.size();
  out.ratio = out.low = out.high = kNaN;
  if (raw_errors_m.empty()) return out;
  const std::vector<double> r = squares(raw_errors_m), c = squares(corrected_errors_m);
  const double mr = mean(r), mc = mean(c);
  if (!(mc > 0.0)) return out;
  out.ratio = mr / mc;
  if (r.size() < 2 || !(mr > 0.0)) return out;
  const double var_log = covarianceOfMeans(r, r) / (mr * mr) + covarianceOfMeans(c, c) / (mc * mc) -
                         2.0 * covarianceOfMeans(r, c) / (mr * mc);
  const double half =
      centralTFactor(level, static_cast<double>(r.size() - 1)) * std::sqrt(std::max(var_log, 0.0));
  out.low = out.ratio * std::exp(-half);
  out.high = out.ratio * std::exp(half);
  return out;
}

}  // namespace lidarcal::calibration
