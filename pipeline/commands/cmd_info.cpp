// SPDX-License-Identifier: BSD-3-Clause
// lidarcal info SEQ: what is in a scan sequence.

#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/summary.hpp"

namespace lidarcal::pipeline {

void addInfoCommand(CLI::App& app) {
  auto seq_dir = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  CLI::App* sub = app.add_subcommand(
      "info", "Summarise a scan sequence (scans, stops, beams, ranges, metadata)");
  sub->add_option("SEQ", *seq_dir, "Sequence directory (.pcd files, see docs/FORMAT.md)")
      ->required();
  sub->add_flag("--json", *json, "Print the summary as JSON (for scripts) instead of Markdown");
  sub->callback([seq_dir, json] {
    const io::Sequence seq = io::openSequence(*seq_dir);
    Progress progress("reading", seq.scans.size());
    const SequenceSummary s = summarize(seq, [&](std::size_t done) { progress.update(done); });
    progress.finish();
    if (*json)
      std::printf("%s\n", toJson(seq, s).dump(2).c_str());
    else
      std::fputs(toMarkdown(seq, s).c_str(), stdout);
  });
}

}  // namespace lidarcal::pipeline
