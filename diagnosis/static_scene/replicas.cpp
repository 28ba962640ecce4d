// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/static_scene/replicas.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "common/rng.hpp"
#include "simulation/simulator.hpp"

namespace lidarcal::diagnosis::static_scene {

BinnedReadings simulateStatic(const BinnedReadings& d, const std::vector<BinFit>& f,
                              const WallFit& w, const ReadingModel& m, std::uint64_t seed,
                              const RangeEffects& fx) {
  BinnedReadings r = d;
  RangeModel rm;
  rm.bias.alpha = {w.ok ? w.alpha0 : 0.0, 1.0};
  rm.noise.kind = NoiseKind::power;
  rm.noise.exponent = m.kappa;
  rm.noise.sigma_e = m.sigma_e;
  rm.range_min_m = -1e9;
  rm.range_max_m = 1e9;
  auto rough = makeRng(seed, 0x3A11ULL);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> u(d.bins.size(), 0.0);
  for (double& v : u) v = (w.ok ? w.tau : 0.0) * normal(rough);
  std::map<std::size_t, std::size_t> wall_index;
  for (std::size_t k = 0; k < w.bins.size(); ++k) wall_index[w.bins[k]] = k;
  std::vector<std::mt19937_64> gens;
  std::map<std::uint32_t, std::size_t> gen_of;
  for (std::size_t i = 0; i < d.y.size(); ++i) {
    const int bi = d.bin_of[i];
    if (bi < 0 || f[static_cast<std::size_t>(bi)].n == 0) continue;
    const Bin& b = d.bins[static_cast<std::size_t>(bi)];
    const BinFit& bf = f[static_cast<std::size_t>(bi)];
    double mean = bf.at(d.a[i], d.t[i]);
    if (w.ok && b.wall >= 0 && wall_index.count(static_cast<std::size_t>(bi))) {
      const Line& l = w.lines[static_cast<std::size_t>(b.wall)];
      mean = w.alpha0 + l.p / std::max(std::cos(d.a[i] - l.theta), 0.05) +
             u[static_cast<std::size_t>(bi)];
    }
    const auto scan = static_cast<std::uint32_t>(d.t[i]);
    auto it = gen_of.find(scan);
    if (it == gen_of.end()) {
      it = gen_of.emplace(scan, gens.size()).first;
      gens.push_back(simulation::effectRng(seed, scan));
    }
    auto& gen = gens[it->second];
    const double e = normal(gen);
    double dist = mean - rm.bias.alpha[0];
    if (fx.mixed_pixel_fraction > 0.0) {
      // At a depth discontinuity the footprint may straddle both surfaces: a reading anywhere
      // between them (the other side is the nearer or the farther one).
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      const double u1 = unit(gen), share = unit(gen);
      if (b.edge && u1 < fx.mixed_pixel_fraction) {
        const double other =
            (std::abs(mean - b.near) < std::abs(mean - b.far) ? b.far : b.near) - rm.bias.alpha[0];
        dist = share * dist + (1.0 - share) * other;
      }
    }
    RangeEffects no_mix = fx;
    no_mix.mixed_pixel_fraction = 0.0;
    const double intensity = std::isfinite(b.intensity) ? b.intensity : 0.0;
    r.y[i] = simulation::effectReading(
        rm, no_mix, dist, simulation::BeamContext{b.cos_inc, 0.0, scan, intensity}, e, gen);
  }
  return r;
}

std::vector<ResidualRecord> residualRecordsOf(const BinnedReadings& dd,
                                              const std::vector<BinFit>& ff,
                                              const ReadingModel& mm) {
  std::vector<ResidualRecord> rec;
  forEachFitted(dd, ff, [&](std::size_t i, const Bin& b, const BinFit& bf) {
    ResidualRecord r;
    r.range_m = bf.m;
    r.incidence_rad = b.inc_known ? std::acos(std::clamp(b.cos_inc, 0.0, 1.0)) : kNaN;
    r.lateral = b.edge ? 1.0 : 0.0;
    r.group = b.wall + 1;
    r.time = dd.t[i];
    r.bearing_rad = b.angle;
    r.edge = b.edge;
    const double centre = bf.at(dd.a[i], dd.t[i]);
    r.residual_m = dd.y[i] - centre;
    r.z = r.residual_m / (mm.sigma_e * shapeOf(mm, b, centre));
    rec.push_back(r);
  });
  return rec;
}

}  // namespace lidarcal::diagnosis::static_scene
