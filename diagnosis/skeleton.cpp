#include "diagnosis/skeleton.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lidarcal::diagnosis {

std::vector<Effect> candidateList(const DiagnoseConfig& config, DiagnoseMode mode) {
  std::vector<Effect> all;
  for (const auto& i : effectTable())
    if ((mode == DiagnoseMode::sequence ? i.sequence_statistic : i.static_statistic) != nullptr) all.push_back(i.effect);
  if (config.candidates.empty()) return all;
  for (Effect e : config.candidates)
    if (std::find(all.begin(), all.end(), e) == all.end())
      throw std::invalid_argument(std::string("diagnose: '") + toString(e) + "' is not a candidate effect for " +
                                  (mode == DiagnoseMode::sequence ? "a sequence" : "a static recording"));
  return config.candidates;
}

const char* statisticOf(Effect e, DiagnoseMode mode) {
  const char* s = mode == DiagnoseMode::sequence ? info(e).sequence_statistic : info(e).static_statistic;
  return s ? s : "";
}

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

void setScore(CandidateResult& r, const std::vector<Discrepancy>& battery) {
  for (const auto& d : battery)
    if (d.name == r.statistic) {
      r.score_p_value = d.p_value;
      r.effect_size = d.effect_size;
    }
}

}  // namespace lidarcal::diagnosis
