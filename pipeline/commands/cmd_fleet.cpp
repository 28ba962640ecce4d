// SPDX-License-Identifier: BSD-3-Clause
// lidarcal fleet INPUT... --out DIR: one view of a fleet's calibrations. Each INPUT is a
// model.json, a `run` output directory (holding model.json) or, with --manifest, a CSV of
// `sensor,date,model` rows that gives each calibration its sensor and date (a sensor's history).
// Writes DIR/fleet.json, DIR/fleet.md and the bias curves (fleet_bias.svg, drawn by
// fleet_bias.gp); the statistics are pipeline/fleet.hpp's.

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "calibration/fleet.hpp"
#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/csv_row.hpp"
#include "io/gnuplot.hpp"
#include "io/model_io.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/reports/fleet_report.hpp"

namespace lidarcal::pipeline {
namespace fs = std::filesystem;
namespace {

struct FleetOptions {
  std::vector<std::string> inputs;
  std::string manifest;
  std::string out;
  calibration::FleetConfig config;
  bool overwrite = false;
};

constexpr const char* kPlot = "fleet_bias.svg";
constexpr const char* kManifestRemedy =
    "a manifest has the header sensor,date,model and one calibration a row (docs/FORMAT.md)";

/// model.json itself, or the one inside a `run` output directory.
fs::path modelFile(const fs::path& input) {
  return fs::is_directory(input) ? input / "model.json" : input;
}

/// YYYY-MM-DD, optionally followed by a time (THH:MM[:SS...]): ordered as text, ordered in time.
bool isoDate(const std::string& d) {
  if (d.size() < 10) return false;
  for (std::size_t i = 0; i < 10; ++i)
    if ((i == 4 || i == 7) ? d[i] != '-' : !std::isdigit(static_cast<unsigned char>(d[i])))
      return false;
  if (d.size() == 10) return true;
  return d[10] == 'T' && d.find_first_not_of("0123456789:.+-Z", 11) == std::string::npos;
}

std::vector<calibration::FleetEntry> readManifest(const fs::path& manifest) {
  io::CsvReader csv(manifest, kManifestRemedy);
  csv.expectHeader("sensor,date,model");
  std::vector<calibration::FleetEntry> entries;
  while (csv.next(3)) {
    calibration::FleetEntry e;
    e.sensor = csv.text(0);
    e.date = csv.text(1);
    if (e.sensor.empty()) csv.fail("sensor", "is empty");
    if (!isoDate(e.date))
      csv.fail("date",
               "'" + e.date + "' is not an ISO 8601 date (YYYY-MM-DD, optionally THH:MM:SS)");
    fs::path model = csv.text(2);
    if (model.is_relative()) model = manifest.parent_path() / model;
    e.source = modelFile(model).string();
    e.model = io::readModel(modelFile(model));
    entries.push_back(std::move(e));
  }
  if (entries.empty())
    throw InputError(manifest.string(), "", "lists no calibration", kManifestRemedy);
  return entries;
}

std::vector<calibration::FleetEntry> readInputs(const std::vector<std::string>& inputs) {
  std::vector<calibration::FleetEntry> entries;
  for (const std::string& input : inputs) {
    calibration::FleetEntry e;
    e.source = modelFile(input).string();
    e.model = io::readModel(modelFile(input));
    e.sensor = e.model.sensor_name;
    if (e.sensor.empty())
      throw InputError(e.source, "sensor.name",
                       "is empty: the fleet report tells sensors apart by name",
                       "give sensor_name in the sequence's sequence.json before calibrating, or "
                       "list the models in a "
                       "--manifest with a sensor column");
    entries.push_back(std::move(e));
  }
  return entries;
}

void runFleet(const FleetOptions& o) {
  if (o.inputs.empty() == o.manifest.empty())
    throw InputError("", "INPUT",
                     o.inputs.empty() ? "no calibration given" : "both inputs and --manifest given",
                     "pass model.json files or run directories, or one --manifest");
  try {
    o.config.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError("", "--distances/--alpha", e.what());
  }
  io::StagedDirectory out(o.out, o.overwrite);
  const std::vector<calibration::FleetEntry> entries =
      o.manifest.empty() ? readInputs(o.inputs) : readManifest(o.manifest);
  const calibration::FleetSummary summary = calibration::summarizeFleet(entries, o.config);
  io::writeTextAtomically(out.path() / "fleet.json", fleetJson(summary).dump(2) + "\n");
  io::writeTextAtomically(out.path() / "fleet_bias.gp", fleetGnuplot(summary, kPlot));
  std::string why;
  const bool plotted = io::runGnuplot(out.path(), "fleet_bias.gp", &why);
  io::writeTextAtomically(out.path() / "fleet.md", fleetMarkdown(summary, plotted ? kPlot : ""));
  out.commit();
  std::printf("Fleet: %zu sensors from %zu calibrations; flagged: %s\n", summary.rows.size(),
              entries.size(),
              summary.flagged.empty() ? "none" : std::to_string(summary.flagged.size()).c_str());
  for (const calibration::FleetRow& r : summary.rows)
    if (r.moved.flagged || r.outlier.flagged)
      std::printf("  %s (%s):%s%s\n", r.current.sensor.c_str(),
                  r.current.date.empty() ? "undated" : r.current.date.c_str(),
                  r.moved.flagged ? " bias moved since its previous calibration" : "",
                  r.outlier.flagged ? " bias differs from the fleet's" : "");
  std::printf("Output: %s (fleet.json, fleet.md, %s)\n", o.out.c_str(),
              plotted ? kPlot : "fleet_bias.gp");
  if (!plotted) std::printf("Plot: %s\n", why.c_str());
}

}  // namespace

void addFleetCommand(CLI::App& app) {
  auto o = std::make_shared<FleetOptions>();
  CLI::App* sub = app.add_subcommand("fleet",
                                     "One view of many calibrations: every sensor's bias at a few "
                                     "distances (+- standard error), noise, status and "
                                     "warnings; flags a sensor whose bias moved since its previous "
                                     "calibration (Wald test with both covariances) or "
                                     "differs from the fleet's median (robust scale), false alarms "
                                     "held to --alpha over the fleet (Holm).");
  sub->add_option("inputs", o->inputs,
                  "model.json files or `lidarcal run` output directories (sensor from the model)");
  sub->add_option(
      "--manifest", o->manifest,
      "CSV with header sensor,date,model (model: model.json or a run directory, "
      "relative to the CSV); dates ISO 8601; a sensor's latest is compared with the one before");
  sub->add_option("-o,--out", o->out, "Output directory (fleet.json, fleet.md, fleet_bias.svg)")
      ->required();
  sub->add_option("--distances", o->config.distances_m,
                  "Distances where the bias is read and compared, metres, increasing")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--alpha", o->config.alpha,
                  "False-alarm rate over the fleet for each test (Holm)")
      ->capture_default_str()
      ->check(CLI::Range(1e-6, 0.5));
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT if it exists");
  sub->callback([o] { runFleet(*o); });
}

}  // namespace lidarcal::pipeline
