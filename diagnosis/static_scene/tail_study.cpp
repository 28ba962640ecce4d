// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/static_scene/tail_study.hpp"

#include <algorithm>
#include <cmath>

#include "common/range_effects.hpp"

namespace lidarcal::diagnosis::static_scene {

std::vector<TailBeam> tailBeams(const BinnedReadings& d, const std::vector<BinFit>& f) {
  double mean_lr = 0.0, n = 0.0;
  for (std::size_t k = 0; k < d.bins.size(); ++k) {
    if (f[k].n == 0) continue;
    mean_lr += std::log(std::max(std::abs(f[k].m), 1e-3));
    n += 1.0;
  }
  mean_lr /= std::max(n, 1.0);
  std::vector<TailBeam> beams(d.bins.size());
  for (std::size_t k = 0; k < d.bins.size(); ++k) {
    const Bin& b = d.bins[k];
    TailBeam& t = beams[k];
    t.log_range = std::log(std::max(std::abs(f[k].m), 1e-3));
    // At a depth edge the tails are the edge's (the bin's mean mixes both surfaces, and the slope
    // it makes with its neighbour may be the jump's): no grazing covariate there. The noise law
    // keeps the incidence (a pillar's silhouette is seen at grazing incidence).
    t.log_sec_inc = b.inc_known ? -std::log(clampCosIncidence(b.cos_inc)) : 0.0;
    t.x[kTailEdge] = b.edge ? 1.0 : 0.0;
    t.x[kTailGrazing] = b.edge ? 0.0 : t.log_sec_inc;
    t.x[kTailRange] = t.log_range - mean_lr;
    // Darkness: how much weaker than the median beam's the return is, ln(I_median / I), >= 0.
    t.x[kTailDark] = std::max(0.0, b.dark);
    t.dark = b.dark;
    if (b.edge && b.far > b.near) {
      t.mix_lo = b.near - f[k].med;
      t.mix_hi = b.far - f[k].med;
    }
  }
  return beams;
}

std::array<bool, kTailCovariates> tailAvailable(const BinnedReadings& d,
                                                const std::vector<TailBeam>& beams,
                                                std::size_t edges) {
  std::array<bool, kTailCovariates> a{};
  a[kTailEdge] = edges >= 3;
  for (int j : {kTailGrazing, kTailRange, kTailDark}) {
    std::vector<double> x;
    for (const auto& b : beams) x.push_back(b.x[static_cast<std::size_t>(j)]);
    const double med = x.empty() ? 0.0 : upperMedian(x);
    std::size_t away = 0;
    for (double v : x) away += std::abs(v - med) > 0.1;
    a[static_cast<std::size_t>(j)] = away >= 3;
  }
  a[kTailDark] = a[kTailDark] && d.intensity;
  return a;
}

std::vector<TailReading> tailResiduals(const BinnedReadings& d, const std::vector<BinFit>& f,
                                       const std::vector<bool>& train, bool held_out,
                                       std::vector<std::size_t>* scans) {
  std::vector<TailReading> out;
  forEachFitted(d, f, [&](std::size_t i, const Bin& b, const BinFit& bf) {
    const bool in_train = train.empty() || train[static_cast<std::size_t>(d.t[i])];
    if (in_train == held_out) return;
    TailReading r;
    r.beam = static_cast<std::size_t>(d.bin_of[i]);
    r.residual_m = d.y[i] - bf.at(d.a[i], d.t[i]) - (b.edge ? bf.med - bf.m : 0.0);
    r.inflation = held_out ? std::sqrt(1.0 + 1.0 / std::max(bf.n, 1.0)) : 1.0;
    out.push_back(r);
    if (scans) scans->push_back(static_cast<std::size_t>(d.t[i]));
  });
  return out;
}

void setupTailSpecs(TailStudy& ts, bool incidence_known, bool edges, bool dark) {
  TailSpec pooled, full;
  full.covariate = ts.available;
  ts.specs = {pooled, full};
  ts.dropped = {-1, -1};
  for (int j = 0; j < kTailCovariates; ++j) {
    if (!ts.available[static_cast<std::size_t>(j)]) continue;
    TailSpec s = full;
    s.covariate[static_cast<std::size_t>(j)] = false;
    ts.specs.push_back(s);
    ts.dropped.push_back(j);
  }
  auto robust = [&](std::size_t& at, auto set) {
    TailSpec s = pooled;
    set(s);
    at = ts.specs.size();
    ts.specs.push_back(s);
    ts.dropped.push_back(-1);
  };
  if (incidence_known) robust(ts.gamma, [](TailSpec& s) { s.gamma = true; });
  robust(ts.kappa, [](TailSpec& s) { s.kappa = true; });
  if (edges) robust(ts.mixed, [](TailSpec& s) { s.mixed = true; });
  if (dark) robust(ts.delta, [](TailSpec& s) { s.delta = true; });
  ts.ll.assign(ts.specs.size(), {});
}

HeldOutGain gainOf(const std::vector<double>& a, const std::vector<double>& b,
                   const std::vector<std::size_t>& block) {
  HeldOut h(1);
  h.base = b;  // deliberate copies: a few vectors, once per diagnosis
  h.cand[0] = a;
  h.block = block;
  h.points = static_cast<double>(a.size());
  return heldOutGain(h, 0);
}

std::string tailClass(const TailModel& m, const TailBeam& b,
                      const std::vector<TailCovariateResult>& covs) {
  std::string cls = "unknown";
  double best = std::log(2.0);
  for (const auto& c : covs) {
    if (!c.significant) continue;
    int j = 0;
    while (c.covariate != tailCovariateName(j)) ++j;
    const double term = m.beta[static_cast<std::size_t>(1 + j)] * b.x[static_cast<std::size_t>(j)];
    if (term > best) {
      best = term;
      cls = c.covariate;
    }
  }
  return cls;
}

}  // namespace lidarcal::diagnosis::static_scene
