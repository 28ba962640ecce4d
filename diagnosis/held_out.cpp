// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/held_out.hpp"

#include <cmath>
#include <map>

#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis {

double HeldOut::baselineMean() const {
  double s = 0.0;
  for (double v : base) s += v;
  return s / points;
}

HeldOutGain heldOutGain(const HeldOut& held, std::size_t candidate) {
  HeldOutGain g;
  std::map<std::size_t, double> per_block;
  double sum = 0.0;
  for (std::size_t i = 0; i < held.base.size(); ++i) {
    const double diff = held.cand[candidate][i] - held.base[i];
    if (!std::isfinite(diff)) g.finite = false;
    sum += diff;
    per_block[held.block[i]] += diff;
  }
  g.gain = sum / held.points;
  double ss = 0.0;
  const double mean_block = sum / static_cast<double>(per_block.size());
  for (const auto& [key, v] : per_block) ss += (v - mean_block) * (v - mean_block);
  const double nb = static_cast<double>(per_block.size());
  g.se = nb > 1 ? std::sqrt(ss / (nb - 1.0) * nb) / held.points : 0.0;
  return g;
}

void setHeldOutGain(CandidateResult& r, const HeldOutGain& g) {
  r.heldout_gain_nats_per_point = g.gain;
  r.heldout_gain_se = g.se;
  r.p_heldout = heldoutPValue(r.heldout_gain_nats_per_point, r.heldout_gain_se);
}

}  // namespace lidarcal::diagnosis
