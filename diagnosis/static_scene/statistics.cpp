// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/static_scene/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "common/stats_util.hpp"
#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis::static_scene {
namespace {

/// Lag-1 correlation over the scans of each bin (the independence check of Alhashimi et al. 2016),
/// pooled, times sqrt(pairs).
double lag1Correlation(const BinnedReadings& d, const std::vector<BinFit>& f) {
  double num = 0.0, den = 0.0, n = 0.0;
  for (std::size_t bi = 0; bi < d.bins.size(); ++bi) {
    if (f[bi].n == 0) continue;
    std::vector<std::pair<double, double>> r;
    for (std::size_t i : d.bins[bi].idx) r.push_back({d.t[i], d.y[i] - f[bi].at(d.a[i], d.t[i])});
    std::sort(r.begin(), r.end());
    for (std::size_t k = 1; k < r.size(); ++k)
      if (r[k].first == r[k - 1].first + 1.0) {
        num += r[k].second * r[k - 1].second;
        n += 1.0;
      }
    for (const auto& v : r) den += v.second * v.second;
  }
  return den > 0.0 ? num / den * std::sqrt(std::max(n, 1.0)) : 0.0;
}

}  // namespace

std::map<std::string, double> staticStatistics(const BinnedReadings& d,
                                               const std::vector<BinFit>& f, const ReadingModel& m,
                                               const WallFit& w0, const WallFit& wb, double q) {
  std::map<std::string, double> st;
  std::vector<double> z, psi, xs, logm, zi, loginc, zc, cb, sb, zd, dark;
  // One recorded value (a driver's constant) leaves darkness at rounding level, which the score,
  // scale-free in its covariate, would read as a covariate.
  const bool dark_varies = darknessVaries(d);
  double pos_e = 0, n_e = 0, pos_i = 0, n_i = 0, s_e = 0, s_i = 0;
  double m2 = 0, m4 = 0, nk = 0;
  std::vector<double> y;
  forEachFitted(d, f, [&](std::size_t i, const Bin& b, const BinFit& bf) {
    const double centre = bf.at(d.a[i], d.t[i]);
    const double s = m.sigma_e * shapeOf(m, b, centre);
    const double zz = (d.y[i] - centre) / s;
    y.push_back(d.y[i]);
    z.push_back(zz);
    psi.push_back(huberPsi(zz));
    xs.push_back((d.t[i] - d.t_mean) / s);
    logm.push_back(std::log(std::max(bf.m, 1e-3)));
    cb.push_back(std::cos(b.angle));
    sb.push_back(std::sin(b.angle));
    zc.push_back(zz);
    if (b.inc_known && !b.edge) {
      zi.push_back(zz);
      loginc.push_back(-std::log(b.cos_inc));
    }
    if (dark_varies && !b.edge) {
      zd.push_back(zz);
      dark.push_back(b.dark);
    }
    const double z2 = std::min(zz * zz, 9.0);
    if (b.edge) {
      n_e += 1;
      pos_e += std::abs(zz) > 3.0;
      s_e += z2;
    } else {
      n_i += 1;
      pos_i += std::abs(zz) > 3.0;
      s_i += z2;
      m2 += zz * zz;
      m4 += zz * zz * zz * zz;
      nk += 1;
    }
  });
  st["spread_vs_range"] = spreadScore(z, logm);
  st["spread_vs_incidence"] = spreadScore(zi, loginc);
  st["spread_vs_intensity"] = spreadScore(zd, dark);
  st["residual_vs_time"] = meanScore(psi, xs);
  {
    const double a = spreadScore(zc, cb), b = spreadScore(zc, sb);
    st["spread_vs_bearing"] = cubeRootChi2(a * a + b * b, 2.0);
  }
  st["edge_excess"] = n_e > 0 && n_i > 0 ? (pos_e - n_e * pos_i / n_i) / std::sqrt(n_e) : 0.0;
  st["edge_vs_centre_spread"] = n_e > 0 && n_i > 0 ? s_e / n_e - s_i / n_i : 0.0;
  st["tail_weight"] = nk > 0 ? (m4 / nk) / std::pow(m2 / nk, 2) - 3.0 : 0.0;
  st["quantisation"] = gridResultant(y, q > 0.0 ? q : 1e-3);
  st["lag1_correlation"] = lag1Correlation(d, f);
  st["wall_curvature"] = wb.ok && wb.b_se > 0.0 && std::isfinite(wb.b_se) ? wb.b / wb.b_se : 0.0;
  st["wall_roughness_mm"] = w0.ok ? 1000.0 * w0.tau : 0.0;
  st["range_offset_mm"] = w0.ok ? 1000.0 * w0.alpha0 : 0.0;
  return st;
}

}  // namespace lidarcal::diagnosis::static_scene
