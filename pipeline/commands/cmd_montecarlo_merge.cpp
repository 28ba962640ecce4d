// SPDX-License-Identifier: BSD-3-Clause
// lidarcal montecarlo-merge SHARD_DIR... --out DIR: puts a Monte Carlo study run in shards
// (`lidarcal montecarlo --shard K/N`) back together. The shards must be the N slices of one
// study, each once (pipeline/stages/montecarlo_shard.hpp checks it and names the file and field
// that differ); the files are then made from the trials' results as the single process makes them,
// so DIR holds the same bytes as `lidarcal montecarlo` without --shard: CSV, summaries, plots.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "io/atomic_file.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/stages/montecarlo_setup.hpp"
#include "pipeline/stages/montecarlo_shard.hpp"
#include "studies/study.hpp"

namespace lidarcal::pipeline {
namespace {

struct MergeOptions {
  std::vector<std::string> shards;
  std::string out;
  bool overwrite = false;
};

void runMerge(const MergeOptions& o) {
  std::vector<std::filesystem::path> dirs(o.shards.begin(), o.shards.end());
  for (const auto& d : dirs) io::checkOutsideInput(d, o.out);
  io::StagedDirectory out(o.out, o.overwrite);
  const MergedStudy merged = readShards(dirs);
  const StudySetup setup = studySetup(merged.options);
  const studies::StudyOutput result =
      studies::studyOutput(setup.figures, setup.grids, setup.config, setup.run, merged.results);
  const std::string plots = writeStudyOutput(out.path(), result);
  out.commit();
  std::printf("Monte Carlo study merged from %zu shards: %zu cells x %zu trials\n", dirs.size(),
              result.cells, setup.run.trials);
  std::printf("Output: %s (summary.md; per figure .csv, .png, .gp, .md)\n", o.out.c_str());
  if (!plots.empty()) std::printf("Plots: %s\n", plots.c_str());
}

}  // namespace

void addMonteCarloMergeCommand(CLI::App& app) {
  auto o = std::make_shared<MergeOptions>();
  CLI::App* sub = app.add_subcommand("montecarlo-merge",
                                     "Merges the shards of a Monte Carlo study (`montecarlo "
                                     "--shard K/N`, one directory each) into the files the "
                                     "whole study writes, byte for byte. Every slice 1..N must be "
                                     "given once, all of one study (same --study, "
                                     "--seed, --trials and options); otherwise nothing is written "
                                     "and the command exits 2 naming the file and field.");
  sub->add_option("shards", o->shards, "The shard directories (any order)")->required();
  sub->add_option("-o,--out", o->out,
                  "Output directory (created whole at the end; see docs/FORMAT.md)")
      ->required();
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT if it exists");
  sub->callback([o] { runMerge(*o); });
}

}  // namespace lidarcal::pipeline
