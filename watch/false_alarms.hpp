// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How the alarm keeps the false-alarm rate the user sets. Checks come when the poles allow
// (model_check.hpp), each on the stretch of driving since the previous completed check. The
// check that completes after an exposure E_k (kilometres or hours since the previous completed
// check) is a test of size
//     alpha_k = rate x E_k          (at most kMaxLevel),
// an alarm when its p-value falls below alpha_k. Summed over the checks, the expected number of
// alarms while the sensor matches the model is rate x (exposure covered), whatever the spacing
// of the checks: alpha spending in exposure. The stretches are disjoint, so the decisions are
// independent but for the model's own error, which every check shares and each counts in its
// covariance.

#include "watch/watch_settings.hpp"

namespace lidarcal::watch {

/// The largest level a single check is given (an exposure so long that rate x E would exceed it
/// spends only this).
inline constexpr double kMaxLevel = 0.5;

class FalseAlarmBudget {
 public:
  explicit FalseAlarmBudget(const FalseAlarmRate& rate) : rate_(rate) {}
  /// Adds exposure: `km` travelled and `hours` driven; the rate's unit picks one.
  void expose(double km, double hours) { pending_ += rate_.unit == Exposure::time ? hours : km; }
  /// The exposure waiting for the next decision, in the rate's unit.
  double pending() const { return pending_; }
  /// The level of the decision made now; the exposure starts again from zero.
  double spend() {
    const double level = rate_.per_unit * pending_;
    pending_ = 0.0;
    return level < kMaxLevel ? level : kMaxLevel;
  }

 private:
  FalseAlarmRate rate_;
  double pending_ = 0.0;
};

}  // namespace lidarcal::watch
