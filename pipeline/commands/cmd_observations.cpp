// SPDX-License-Identifier: BSD-3-Clause
// Observation-level data for noise estimation:
//   lidarcal simulate --scene SCENE.json (with "kind": "observations") --out DIR [--seed N]
//     writes DIR/observations.csv, DIR/odometry.csv and DIR/noise_truth.json;
//   lidarcal landmarks-to-observations --landmarks landmarks.csv --sequence SEQ --out DIR
//     converts detection output (and the sequence's commanded stop poses) to the same files.

#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/landmarks_to_observations.hpp"
#include "io/noise_json.hpp"
#include "io/observations_csv.hpp"
#include "io/sequence.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/words.hpp"
#include "simulation/observation_sim.hpp"

namespace lidarcal::pipeline {

void simulateObservationScene(const std::string& scene_file, const std::string& out_dir,
                              std::uint64_t seed, bool overwrite) {
  const ObservationScene scene = io::readObservationScene(scene_file);
  io::StagedDirectory out(out_dir, overwrite);
  const simulation::ObservationSimulation sim = simulation::simulateObservations(scene, seed);
  io::writeObservations(out.path() / "observations.csv", sim.observations);
  io::writeOdometry(out.path() / "odometry.csv", sim.odometry);
  io::writeNoiseTruth(out.path() / "noise_truth.json", io::NoiseTruth{seed, scene, sim.true_poses});
  out.commit();
  if (!quiet())
    std::fprintf(stderr, "simulated %s by %s at %s into %s\n",
                 plural(sim.observations.size(), "observation").c_str(),
                 plural(scene.sensors.size(), "sensor").c_str(),
                 plural(sim.odometry.size(), "stop").c_str(), out_dir.c_str());
}

namespace {

struct ConvertOptions {
  std::string landmarks, sequence, out, range_to = "centre";
  bool overwrite = false;
};

void runConvert(const ConvertOptions& o) {
  const io::Sequence seq = io::openSequence(o.sequence);
  const auto reference =
      o.range_to == "surface" ? io::RangeReference::surface : io::RangeReference::centre;
  const std::vector<Observation> observations =
      io::observationsFromLandmarksCsv(o.landmarks, reference);
  for (const auto& obs : observations)
    if (obs.stop >= static_cast<int>(seq.stops.size()))
      throw InputError(
          o.landmarks, "stop " + std::to_string(obs.stop),
          "is not a stop of the sequence (it has " + std::to_string(seq.stops.size()) + ")",
          "give the sequence the landmarks were detected in");
  io::StagedDirectory out(o.out, o.overwrite);
  io::writeObservations(out.path() / "observations.csv", observations);
  io::writeOdometry(out.path() / "odometry.csv", io::odometryFromStops(seq.stops));
  out.commit();
  if (!quiet())
    std::fprintf(stderr, "converted %s at %s into %s\n",
                 plural(observations.size(), "detection").c_str(),
                 plural(seq.stops.size(), "stop").c_str(), o.out.c_str());
}

}  // namespace

void addLandmarksToObservationsCommand(CLI::App& app) {
  auto o = std::make_shared<ConvertOptions>();
  CLI::App* sub = app.add_subcommand("landmarks-to-observations",
                                     "Convert detection's landmarks.csv and the sequence's stop "
                                     "poses to observations.csv + odometry.csv");
  sub->add_option("--landmarks", o->landmarks, "landmarks.csv written by `lidarcal detect`")
      ->required();
  sub->add_option("--sequence", o->sequence,
                  "The sequence the landmarks were detected in (its VIEWPOINTs give the odometry)")
      ->required();
  sub->add_option("-o,--out", o->out, "Output directory: OUT/observations.csv, OUT/odometry.csv")
      ->required();
  sub->add_option("--range-to", o->range_to,
                  "centre: range to the landmark's centre; surface: minus its radius")
      ->check(CLI::IsMember({"centre", "surface"}))
      ->capture_default_str();
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT if it exists");
  sub->callback([o] { runConvert(*o); });
}

}  // namespace lidarcal::pipeline
