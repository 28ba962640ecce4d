// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The decision on each check, made against the watcher's own record of the checks that passed
// (a self-starting control chart: Hawkins 1987, Quesenberry 1991). A check gives the shift s_k
// of the corrected readings at the two reference distances and the fit's covariance C_k of it.
// Over a drive the fit's covariance is right in shape but not always in scale (a pose per scan,
// thin poles: model_check.hpp), and a fit may carry a bias of its own, the same at every check.
// So the checks are taken as
//     s_k = b + u_k + e_k,   u_k ~ N(0, tau^2 I),   e_k ~ N(0, phi^2 C_k),
// b the fit's bias plus the model's own error, u_k what a stretch's geometry adds to it (which
// poles, at which distances, on a straight or a turn), phi^2 the fits' scale. All three are
// estimated from the record of checks under the model in use: tau^2 by restricted maximum
// likelihood, then with weights W_j = (C_j + tau^2 I)^-1
//     b^ = (sum W_j)^-1 sum W_j s_j,   V_b = (sum W_j)^-1,
//     phi^2^ = sum (s_j - b^)^T W_j (s_j - b^) / nu,   nu = q (n - 1),
// q = 2 coordinates of s, n checks (the scale of Knapp & Hartung 2003 for random-effects
// meta-analysis). For a new check k, independent of them,
//     change:    F = (s_k - b^)^T (C_k + tau^2^ I + V_b)^-1 (s_k - b^) / (q phi^2^)  ~ F(q, nu),
// exactly when tau^2 is known, nearly when it is estimated, whatever b is. Once the record
// holds `baseline` checks, the model itself is tested (a unit swapped before the watcher
// started, a model of another sensor): with C_model the model's own error at the distances,
//     absolute:  F = b^T (phi^2^ V_b + C_model)^-1 b^ / q                            ~ F(q, nu)
//     nearly. Two records, the checks before an alarm and those after it, are compared with
// tau^2 and phi^2 shared and a mean each (nu = q (n_1 + n_2 - 2)):
//     same mean: F = (b^_2 - b^_1)^T (V_1 + V_2)^-1 (b^_2 - b^_1) / (q phi^2^)        ~ F(q, nu).
// The levels come from false_alarms.hpp.

#include <cstddef>
#include <deque>

#include <Eigen/Core>

namespace lidarcal::watch {

/// One check's shift at the reference distances and its covariance, as a test takes it.
struct Shift {
  Eigen::Vector2d s = Eigen::Vector2d::Zero();  ///< metres
  Eigen::Matrix2d c = Eigen::Matrix2d::Zero();  ///< m^2
};

/// An F test's result.
struct FTest {
  double statistic = 0.0;  ///< F
  double dof1 = 0.0;       ///< numerator degrees of freedom (q)
  double dof2 = 0.0;       ///< denominator degrees of freedom (nu)
  double p = 1.0;          ///< P(F(dof1, dof2) >= statistic)
};

class ShiftHistory {
 public:
  /// Keeps the last `capacity` checks (>= 2): old checks leave, so the record follows slow drift
  /// of the fit's bias without holding a drive's whole history.
  explicit ShiftHistory(std::size_t capacity = 50);
  void add(const Shift& shift);
  void clear() { shifts_.clear(); }
  std::size_t size() const { return shifts_.size(); }

  /// The change test of `now` against the record; needs size() >= 2.
  FTest change(const Shift& now) const;
  /// The test of the record's mean shift against zero; needs size() >= 2.
  FTest absolute(const Eigen::Matrix2d& model_covariance) const;
  /// The test that this record's checks have the mean of `earlier`'s (the same fits over other
  /// stretches); needs at least three checks in the two.
  FTest sameMean(const ShiftHistory& earlier) const;
  /// The estimated mean shift b^.
  Eigen::Vector2d mean() const;

 private:
  std::size_t capacity_;
  std::deque<Shift> shifts_;
};

/// P(F(d1, d2) >= f).
double fTail(double f, double d1, double d2);

}  // namespace lidarcal::watch
