// SPDX-License-Identifier: BSD-3-Clause
// The gnuplot scripts of the Monte Carlo figures (Alhashimi et al. 2021, Figs. 7-11).
#include <algorithm>
#include <cmath>
#include <string>

#include "studies/figure_text.hpp"
#include "studies/figures.hpp"

namespace lidarcal::studies {
namespace {

std::string gnuplotFig7or8(Figure f, const std::vector<CellSummary>& cells, const StudyGrids& g,
                           const StudyMeta& meta) {
  const bool vsL = f == Figure::fig8;
  std::string s = preamble(std::string(toString(f)) + ".png", 1800, 520);
  std::vector<Series> bias, variance, median;
  const std::size_t curves = vsL ? g.sigma_s_vs_landmarks_m.size() : g.sigma_theta_deg.size();
  for (std::size_t i = 0; i < curves; ++i)
    for (PositionEstimator e : ranPositionEstimators(cells)) {
      std::vector<std::vector<double>> rows;
      if (vsL) {
        for (int L : g.landmarks)
          if (const auto* c =
                  find(cells, L, g.sigma_s_vs_landmarks_m[i], g.sigma_theta_vs_landmarks_deg))
            rows.push_back({static_cast<double>(L), positionOf(*c, e).bias_m,
                            positionOf(*c, e).variance_m2, positionOf(*c, e).error_m.median});
      } else {
        for (double ss : g.sigma_s_m)
          if (const auto* c = find(cells, g.fig7_landmarks, ss, g.sigma_theta_deg[i]))
            rows.push_back({ss * 100.0, positionOf(*c, e).bias_m, positionOf(*c, e).variance_m2,
                            positionOf(*c, e).error_m.median});
      }
      const std::string name = "d" + std::to_string(i) + "_" + toString(e);
      s += block(name, rows);
      const std::string style = "with linespoints lw 2 pt 7 ps 0.8 lc rgb \"" + colour(i) + "\"" +
                                (e == PositionEstimator::joint ? " dt 2" : "");
      const std::string label =
          (vsL ? sigmaText(g.sigma_s_vs_landmarks_m[i]) : thetaText(g.sigma_theta_deg[i])) + ", " +
          positionLabel(e);
      bias.push_back({"$" + name, "1:2", label, style});
      variance.push_back({"$" + name, "1:3", label, style});
      median.push_back({"$" + name, "1:4", label, style});
    }
  const std::string title =
      vsL ? "Fig. 8: landmark position vs L (" + thetaText(g.sigma_theta_vs_landmarks_deg) + ")"
          : "Fig. 7: landmark position vs σ_s (L = " + std::to_string(g.fig7_landmarks) + ")";
  s += "set multiplot layout 1,3 title \"" + title +
       (ran(cells, Estimator::joint) ? "; solid: paper, dashed: joint; " : "; ") +
       std::to_string(meta.config.path.scans_per_stop) + " scans/stop\"\n";
  const std::string x = vsL ? "set xlabel \"landmarks L\"\nset xtics 1\nset logscale y\n"
                            : "set xlabel \"σ_s (cm)\"\nset logscale xy\n";
  s += panel("bias (length of the mean error)", x + "set ylabel \"bias (m)\"\n", bias);
  s += panel("variance (trace of the covariance)", x + "set ylabel \"variance (m²)\"\n", variance);
  s += panel("median error (robust to runaway trials)", x + "set ylabel \"median error (m)\"\n",
             median);
  return s + "unset multiplot\n";
}

std::string gnuplotFig9(const std::vector<CellSummary>& cells, const StudyGrids& g) {
  const int rows = static_cast<int>(g.fig9_landmarks.size());
  const std::vector<Estimator> estimators = ranEstimators(cells);
  const int columns = static_cast<int>(estimators.size());
  std::string s = preamble("fig9.png", 500 * columns, 450 * rows);
  std::string body;
  std::size_t id = 0;
  std::vector<double> all;
  for (const auto& c : cells)
    for (Estimator e : estimators) all.push_back(ratioStats(c, e).q.median);
  const std::string range = decadeRange(all);
  for (int L : g.fig9_landmarks)
    for (Estimator e : estimators) {
      std::vector<Series> series;
      for (std::size_t i = 0; i < g.sigma_theta_deg.size(); ++i) {
        std::vector<std::vector<double>> data;
        for (double ss : g.sigma_s_m)
          if (const auto* c = find(cells, L, ss, g.sigma_theta_deg[i])) {
            const auto& q = ratioStats(*c, e).q;
            data.push_back({ss * 100.0, q.median, q.q25, q.q75});
          }
        const std::string name = "r" + std::to_string(id++);
        s += block(name, data);
        series.push_back({"$" + name, "1:2", thetaText(g.sigma_theta_deg[i]),
                          "with linespoints lw 2 pt 7 ps 0.8 lc rgb \"" + colour(i) + "\""});
      }
      body += panel(
          estimatorLabel(e) + ", L = " + std::to_string(L),
          "set logscale xy\nset xlabel \"σ_s (cm)\"\nset ylabel \"median MSE ratio\"\n" + range,
          series);
    }
  s += "set multiplot layout " + std::to_string(rows) + "," + std::to_string(columns) +
       " title \"Fig. 9: MSE ratio (eq. 31) over σ_θ × σ_s\"\n";
  return s + body + "unset multiplot\n";
}

std::string gnuplotFig10(const std::vector<CellSummary>& cells, const StudyGrids& g) {
  const std::vector<Estimator> estimators = ranEstimators(cells);
  std::string s = preamble("fig10.png", 500 * static_cast<int>(estimators.size()), 480);
  std::string body;
  std::size_t id = 0;
  for (Estimator e : estimators) {
    std::vector<Series> series;
    for (std::size_t i = 0; i < g.sigma_theta_deg.size(); ++i) {
      std::vector<std::vector<double>> data;
      for (double ss : g.sigma_s_m)
        if (const auto* c = find(cells, g.fig10_landmarks, ss, g.sigma_theta_deg[i]))
          data.push_back({ss * 100.0, orderRate(ratioOf(*c, e), 2), orderRate(ratioOf(*c, e), 1)});
      const std::string name = "o" + std::to_string(id++);
      s += block(name, data);
      const std::string lc = " lc rgb \"" + colour(i) + "\"";
      series.push_back({"$" + name, "1:2", thetaText(g.sigma_theta_deg[i]) + ", n̂ = 2",
                        "with linespoints lw 2 pt 7 ps 0.8" + lc});
      series.push_back({"$" + name, "1:3", thetaText(g.sigma_theta_deg[i]) + ", n̂ = 1",
                        "with linespoints lw 2 pt 6 ps 0.8 dt 2" + lc});
    }
    body += panel(estimatorLabel(e),
                  "set logscale x\nset xlabel \"σ_s (cm)\"\nset ylabel \"rate\"\nset yrange "
                  "[0:1.05]\nset key center left\n",
                  series);
    body += "set yrange [*:*]\n";
  }
  s += "set multiplot layout 1," + std::to_string(estimators.size()) +
       " title \"Fig. 10: selected model order by AIC (true n = 2), L = " +
       std::to_string(g.fig10_landmarks) + "\"\n";
  return s + body + "unset multiplot\n";
}

std::string gnuplotFig11(const std::vector<CellSummary>& cells, const StudyGrids& g) {
  const std::vector<Estimator> estimators = ranEstimators(cells);
  std::string s = preamble("fig11.png", 500 * static_cast<int>(estimators.size()), 480);
  std::string body;
  std::size_t id = 0;
  std::vector<double> all;
  for (const auto& c : cells)
    for (Estimator e : estimators) {
      all.push_back(ratioStats(c, e).q.q25);
      all.push_back(ratioStats(c, e).q.q75);
    }
  const std::string range = decadeRange(all);
  for (Estimator e : estimators) {
    std::vector<Series> series;
    for (std::size_t i = 0; i < g.sigma_s_vs_landmarks_m.size(); ++i) {
      std::vector<std::vector<double>> data;
      for (int L : g.landmarks)
        if (const auto* c =
                find(cells, L, g.sigma_s_vs_landmarks_m[i], g.sigma_theta_vs_landmarks_deg)) {
          const auto& q = ratioStats(*c, e).q;
          data.push_back({static_cast<double>(L), q.median, q.q25, q.q75});
        }
      const std::string name = "l" + std::to_string(id++);
      s += block(name, data);
      series.push_back({"$" + name, "1:2:3:4", sigmaText(g.sigma_s_vs_landmarks_m[i]),
                        "with yerrorlines lw 2 pt 7 ps 0.8 lc rgb \"" + colour(i) + "\""});
    }
    body += panel(estimatorLabel(e),
                  "set logscale y\nset xtics 1\nset xlabel \"landmarks L\"\nset ylabel \"MSE ratio "
                  "(median, quartiles)\"\n" +
                      range,
                  series);
  }
  s += "set multiplot layout 1," + std::to_string(estimators.size()) +
       " title \"Fig. 11: MSE ratio vs L (" + thetaText(g.sigma_theta_vs_landmarks_deg) + ")\"\n";
  return s + body + "unset multiplot\n";
}

}  // namespace

std::string figureGnuplot(Figure f, const std::vector<CellSummary>& cells, const StudyGrids& grids,
                          const StudyMeta& meta) {
  std::string s = "# " + std::string(toString(f)) + ": " + settingsText(meta) +
                  "\n# Regenerate the PNG: gnuplot " + toString(f) + ".gp\n";
  switch (f) {
    case Figure::fig7:
    case Figure::fig8:
      return s + gnuplotFig7or8(f, cells, grids, meta);
    case Figure::fig9:
      return s + gnuplotFig9(cells, grids);
    case Figure::fig10:
      return s + gnuplotFig10(cells, grids);
    case Figure::fig11:
      return s + gnuplotFig11(cells, grids);
  }
  return s;
}

}  // namespace lidarcal::studies
