// SPDX-License-Identifier: BSD-3-Clause
#include "studies/study.hpp"

#include <algorithm>
#include <stdexcept>

#include "studies/statistics.hpp"

namespace lidarcal::studies {
namespace {

bool sameCell(const Cell& a, const Cell& b) {
  return a.landmarks == b.landmarks && a.sigma_s_m == b.sigma_s_m &&
         a.sigma_theta_rad == b.sigma_theta_rad;
}

}  // namespace

std::vector<Cell> studyCells(const std::vector<Figure>& figures, const StudyGrids& grids) {
  std::vector<Cell> cells;
  for (Figure f : figures)
    for (const Cell& c : figureCells(f, grids))
      if (std::none_of(cells.begin(), cells.end(), [&](const Cell& x) { return sameCell(x, c); }))
        cells.push_back(c);
  return cells;
}

StudyOutput runStudy(const std::vector<Figure>& figures, const StudyGrids& grids,
                     const TrialConfig& config, const RunOptions& options) {
  if (options.shard_count != 1)
    throw std::invalid_argument("runStudy: a shard is not a whole study (runCells)");
  const std::vector<Cell> cells = studyCells(figures, grids);
  const StudyRun run = runCells(config, cells, options);
  if (run.interrupted) {
    StudyOutput out;
    out.cells = cells.size();
    out.interrupted = true;
    return out;
  }
  return studyOutput(figures, grids, config, options, run.results);
}

StudyOutput studyOutput(const std::vector<Figure>& figures, const StudyGrids& grids,
                        const TrialConfig& config, const RunOptions& options,
                        const std::vector<std::vector<TrialResult>>& results) {
  StudyOutput out;
  const std::vector<Cell> cells = studyCells(figures, grids);
  if (results.size() != cells.size())
    throw std::invalid_argument("studyOutput: one result list per cell expected");
  out.cells = cells.size();
  std::vector<CellSummary> summaries;
  for (std::size_t i = 0; i < cells.size(); ++i)
    summaries.push_back(summarize(cells[i], results[i], config.max_order));
  StudyMeta meta;
  meta.config = config;
  meta.seed = options.seed;
  meta.trials = options.trials;
  meta.joint_trials = options.joint_trials;
  std::string summary =
      "# Monte Carlo study of Alhashimi et al. 2021 (Figs. 7-11)\n\n"
      "Estimators: the paper's closed form (triangulation, section 3.1; least squares and AIC, "
      "section 3.2), our joint refinement, and the oracle (the paper's fit against the true "
      "distances). MSE ratio: eq. 31 on a fresh draw of the same layout. Columns: "
      "docs/FORMAT.md.\n\n";
  for (Figure f : figures) {
    std::vector<CellSummary> mine;
    for (const Cell& c : figureCells(f, grids))
      for (const CellSummary& s : summaries)
        if (sameCell(s.cell, c)) mine.push_back(s);
    const std::string name = toString(f);
    const std::string md = figureSummary(f, mine, grids, meta);
    out.files.emplace_back(name + ".csv", figureCsv(f, mine, meta));
    out.files.emplace_back(name + ".gp", figureGnuplot(f, mine, grids, meta));
    out.files.emplace_back(name + ".md", "# Monte Carlo study of Alhashimi et al. 2021\n\n" + md);
    out.gnuplot_scripts.push_back(name + ".gp");
    summary += md + "\n";
  }
  out.files.emplace_back("summary.md", summary);
  return out;
}

}  // namespace lidarcal::studies
