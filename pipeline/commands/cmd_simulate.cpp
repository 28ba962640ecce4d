// SPDX-License-Identifier: BSD-3-Clause
// lidarcal simulate --scene SCENE.json --out DIR [--seed N]
// Writes DIR/scans/ (the sequence), DIR/truth.json and DIR/true_ranges.csv.

#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>

#include "io/atomic_file.hpp"
#include "io/noise_json.hpp"
#include "io/output_files.hpp"
#include "io/scene_io.hpp"
#include "io/sequence.hpp"
#include "io/true_ranges.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/words.hpp"
#include "simulation/simulator.hpp"

namespace lidarcal::pipeline {
namespace {

struct SimulateOptions {
  std::string scene;
  std::string out;
  std::uint64_t seed = 1;
  bool ascii = false;
  bool overwrite = false;
  int stops = 0;           // 0: as in the scene
  int scans_per_stop = 0;  // 0: as in the scene
};

void runSimulate(const SimulateOptions& o) {
  namespace fs = std::filesystem;
  io::checkOutsideInput(o.scene, o.out);
  if (io::readSceneKind(o.scene) == "observations") {  // observation-level scene (noise estimation)
    simulateObservationScene(o.scene, o.out, o.seed, o.overwrite);
    return;
  }
  Scene scene = io::readScene(o.scene);
  if (o.stops > 0) scene.path.stops = o.stops;
  if (o.scans_per_stop > 0) scene.path.scans_per_stop = o.scans_per_stop;

  io::StagedDirectory out(o.out, o.overwrite);
  const fs::path scans_dir = out.path() / "scans";
  io::makeDirectory(scans_dir);

  Truth truth;
  truth.seed = o.seed;
  truth.scene = scene;
  truth.stops = simulation::planStops(scene, o.seed);

  io::SequenceMeta meta;
  meta.sensor_name = scene.sensor.name;
  meta.range_min_m = scene.sensor.range.range_min_m;
  meta.range_max_m = scene.sensor.range.range_max_m;
  meta.beams = scene.sensor.beams;
  if (scene.publish_landmark_radius && !scene.landmarks.empty()) {
    bool common = true;
    for (const auto& l : scene.landmarks)
      common = common && l.radius_m == scene.landmarks.front().radius_m;
    if (common) meta.landmark_radius_m = scene.landmarks.front().radius_m;
  }
  io::writeSequenceMeta(scans_dir / "sequence.json", meta);

  io::TrueRangesWriter ranges(out.path() / truth.true_ranges_file);
  const std::size_t total = static_cast<std::size_t>(scene.path.stops) *
                            static_cast<std::size_t>(scene.path.scans_per_stop);
  Progress progress("simulate", total);
  std::size_t done = 0;
  simulation::forEachScan(
      scene, truth.stops, o.seed, [&](std::size_t, simulation::SimulatedScan&& sim) {
        io::writeScan(scans_dir / sim.scan.name, sim.scan,
                      o.ascii ? io::PcdEncoding::ascii : io::PcdEncoding::binary);
        for (const auto& row : sim.truth) ranges.write(row);
        progress.update(++done);
      });
  ranges.close();
  progress.finish();
  io::writeTruth(out.path() / "truth.json", truth);
  out.commit();
  if (!quiet())
    std::fprintf(stderr, "simulated %s at %s into %s (sequence: %s)\n",
                 plural(total, "scan").c_str(),
                 plural(static_cast<std::size_t>(scene.path.stops), "stop").c_str(), o.out.c_str(),
                 (fs::path(o.out) / "scans").c_str());
}

}  // namespace

void addSimulateCommand(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* sub =
      app.add_subcommand("simulate", "Simulate a scan sequence of a scene, with its ground truth");
  sub->add_option("--scene", o->scene, "Scene file (JSON, see docs/FORMAT.md and data/scenes/)")
      ->required();
  sub->add_option("-o,--out", o->out,
                  "Output directory: OUT/scans/ (sequence), OUT/truth.json, OUT/true_ranges.csv")
      ->required();
  sub->add_option("--seed", o->seed, "Random seed; the same scene and seed give the same bytes")
      ->capture_default_str();
  sub->add_option("--stops", o->stops, "Override the scene's number of stops")
      ->check(CLI::PositiveNumber);
  sub->add_option("--scans-per-stop", o->scans_per_stop, "Override the scene's scans per stop")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--ascii", o->ascii, "Write ASCII PCD instead of binary");
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT if it exists");
  sub->callback([o] { runSimulate(*o); });
}

}  // namespace lidarcal::pipeline
