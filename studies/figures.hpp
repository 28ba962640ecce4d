// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The five Monte Carlo figures of Alhashimi et al. 2021 (sections 4.1-4.2) as study grids, and what
// is written for each: a CSV of every cell, a gnuplot script (data inline) for the PNG, and a
// Markdown summary that sets our numbers against the paper's claims. Text only: the pipeline writes
// the files and runs gnuplot.
//   Fig. 7: landmark position bias and variance vs sigma_s, several sigma_theta, L = 1
//   Fig. 8: the same vs L, sigma_theta = 2 degrees
//   Fig. 9: MSE ratio (eq. 31) over sigma_theta x sigma_s, L = 2 and L = 5
//   Fig. 10: rate of each selected order over sigma_theta x sigma_s, L = 2
//   Fig. 11: MSE ratio vs L for several sigma_s, sigma_theta = 2 degrees

#include <cstdint>
#include <string>
#include <vector>

#include "studies/statistics.hpp"
#include "studies/trial.hpp"

namespace lidarcal::studies {

enum class Figure { fig7, fig8, fig9, fig10, fig11 };
const char* toString(Figure f);
bool parseFigure(const std::string& name, Figure& f);
/// All five, in order.
std::vector<Figure> allFigures();

/// The grids the figures are drawn on.
struct StudyGrids {
  /// Figs. 7, 9, 10 (metres)
  std::vector<double> sigma_s_m = {0.001, 0.003, 0.01, 0.03, 0.1, 0.3};
  std::vector<double> sigma_theta_deg = {0.5, 1.0, 2.0, 5.0};  ///< Figs. 7, 9, 10 (degrees)
  std::vector<int> landmarks = {1, 2, 3, 4, 5, 6, 8};          ///< Figs. 8, 11
  std::vector<double> sigma_s_vs_landmarks_m = {0.001, 0.01, 0.03, 0.1};  ///< Figs. 8, 11 (metres)
  double sigma_theta_vs_landmarks_deg = 2.0;                              ///< Figs. 8, 11 (degrees)
  std::vector<int> fig9_landmarks = {2, 5};                               ///< Fig. 9
  int fig10_landmarks = 2;                                                ///< Fig. 10
  int fig7_landmarks = 1;                                                 ///< Fig. 7
  /// A coarse grid for a quick look (--quick).
  static StudyGrids quick();
};

/// Cells of a figure, in output order.
std::vector<Cell> figureCells(Figure f, const StudyGrids& grids);

/// What the outputs say about how they were made.
struct StudyMeta {
  TrialConfig config;            ///< the trial settings
  std::uint64_t seed = 1;        ///< study seed
  std::size_t trials = 0;        ///< trials per cell
  std::size_t joint_trials = 0;  ///< of which the first this many ran the joint refinement
  int threads = 1;               ///< not written (the outputs do not depend on it)
};

/// CSV, one row per cell: parameters, then for each estimator the median and quartiles of each
/// metric (columns documented in docs/FORMAT.md, "montecarlo").
std::string figureCsv(Figure f, const std::vector<CellSummary>& cells, const StudyMeta& meta);

/// gnuplot script writing `<figure>.png` in the current directory; the data are inline.
std::string figureGnuplot(Figure f, const std::vector<CellSummary>& cells, const StudyGrids& grids,
                          const StudyMeta& meta);

/// Markdown: the settings, a table of the figure's numbers, and the paper's claims checked.
std::string figureSummary(Figure f, const std::vector<CellSummary>& cells, const StudyGrids& grids,
                          const StudyMeta& meta);

}  // namespace lidarcal::studies
