// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/montecarlo_setup.hpp"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <thread>
#include <type_traits>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/gnuplot.hpp"

namespace lidarcal::pipeline {
namespace {

std::vector<studies::Figure> figuresOf(const std::string& name) {
  if (name == "all") return studies::allFigures();
  studies::Figure f;
  if (!studies::parseFigure(name, f))
    throw InputError("", "--study", "unknown study '" + name + "'",
                     "use fig7, fig8, fig9, fig10, fig11 or all");
  return {f};
}

studies::TrialConfig trialConfig(const MonteCarloOptions& o) {
  studies::TrialConfig config;
  if (!studies::parseLevel(o.level, config.level))
    throw InputError("", "--level", "unknown level '" + o.level + "'", "use landmark or scan");
  const bool scan = config.level == studies::Level::scan;
  if (!studies::parseAngleNoise(o.angle_noise, config.angle_noise))
    throw InputError("", "--angle-noise", "unknown model '" + o.angle_noise + "'",
                     "use heading, beams or bearing");
  if (!studies::parseNoiseLaw(o.noise_law, config.noise_law))
    throw InputError("", "--noise-law", "unknown law '" + o.noise_law + "'",
                     "use paper or squared");
  if (scan && config.angle_noise != studies::AngleNoise::heading)
    throw InputError("", "--angle-noise",
                     "the scan level models the angle noise as heading noise only",
                     "drop --angle-noise or use heading");
  config.path.scans_per_stop = o.scans_per_stop;
  config.path.stops = o.stops;
  config.path.step_m = o.step_m;
  config.max_order = o.max_order;
  config.placement.max_surface_m = o.max_distance_m;
  config.sensor.range_max_m = o.range_max_m;
  config.noise_scale = o.noise_scale >= 0.0 ? o.noise_scale : (scan ? 0.2 : 1.0);
  try {
    config.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError("", "options", e.what());
  }
  return config;
}

/// Runs every figure's gnuplot script in `dir`. A missing gnuplot is reported (the returned text,
/// empty when every plot was drawn); one that cannot draw here is bad input (InputError naming the
/// package); a script that fails is an error: the command fails and writes nothing, rather than
/// leave a partial picture behind (gnuplot stops at the first failing panel).
std::string drawPlots(const std::filesystem::path& dir, const std::vector<std::string>& scripts) {
  if (!io::gnuplotInstalled())
    return std::string("skipped, gnuplot is not installed (") + io::kGnuplotPackage +
           "); run gnuplot on the .gp files later";
  for (const auto& script : scripts) {
    std::string why;
    if (!io::runGnuplot(dir, script, &why)) {
      if (const std::string broken = io::gnuplotBroken(dir / "gnuplot.log"); !broken.empty())
        throw InputError("", "", broken, "nothing was written");
      throw std::runtime_error("montecarlo: gnuplot failed on " + script +
                               ", nothing was written:\n" + io::gnuplotLog(dir, 2000));
    }
  }
  return "";
}

template <class T>
T field(const nlohmann::json& j, const char* key, const std::string& file) {
  if (!j.contains(key))
    throw InputError(file, key, "missing", "write the shard again with this lidarcal");
  try {
    return j.at(key).get<T>();
  } catch (const nlohmann::json::exception&) {
    throw InputError(file, key, "has the wrong type: " + j.at(key).dump(),
                     "write the shard again with this lidarcal");
  }
}

/// Every option the study's output depends on, by its name in the identity: one list for writing
/// and for reading it back.
template <class Options, class Visit>
void forEachIdentityField(Options& o, Visit&& visit) {
  visit("study", o.study);
  visit("quick", o.quick);
  visit("level", o.level);
  visit("angle_noise", o.angle_noise);
  visit("noise_law", o.noise_law);
  visit("noise_scale", o.noise_scale);
  visit("max_distance_m", o.max_distance_m);
  visit("range_max_m", o.range_max_m);
  visit("stops", o.stops);
  visit("step_m", o.step_m);
  visit("scans_per_stop", o.scans_per_stop);
  visit("max_order", o.max_order);
  visit("seed", o.seed);
  visit("trials", o.trials);
  visit("joint_trials", o.joint_trials);
}

}  // namespace

StudySetup studySetup(const MonteCarloOptions& o) {
  StudySetup s;
  s.figures = figuresOf(o.study);
  s.config = trialConfig(o);
  s.grids = o.quick ? studies::StudyGrids::quick() : studies::StudyGrids{};
  const bool scan = s.config.level == studies::Level::scan;
  // Defaults: the landmark level runs the paper's 1000 trials (100 with --quick), the joint
  // refinement on the first 200 (10); the scan level 100 trials (10), the joint on the first 50
  // (5).
  s.run.trials = o.trials ? o.trials : (scan ? (o.quick ? 10 : 100) : (o.quick ? 100 : 1000));
  s.run.joint_trials =
      o.no_joint
          ? 0
          : (o.joint_trials ? o.joint_trials : (scan ? (o.quick ? 5 : 50) : (o.quick ? 10 : 200)));
  s.run.joint_trials = std::min(s.run.joint_trials, s.run.trials);
  s.run.threads = o.threads > 0
                      ? o.threads
                      : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  s.run.seed = o.seed;
  return s;
}

nlohmann::json studyIdentity(const MonteCarloOptions& o, const StudySetup& s) {
  MonteCarloOptions resolved = o;  // the defaults of the level filled in
  resolved.noise_scale = s.config.noise_scale;
  resolved.trials = s.run.trials;
  resolved.joint_trials = s.run.joint_trials;
  nlohmann::json j;
  j["lidarcal_version"] = LIDARCAL_VERSION;
  forEachIdentityField(resolved, [&](const char* key, const auto& value) { j[key] = value; });
  j["cells"] = studies::studyCells(s.figures, s.grids).size();
  return j;
}

MonteCarloOptions optionsFromIdentity(const nlohmann::json& j, const std::string& file) {
  MonteCarloOptions o;
  forEachIdentityField(o, [&](const char* key, auto& value) {
    value = field<std::decay_t<decltype(value)>>(j, key, file);
  });
  o.no_joint = o.joint_trials == 0;
  if (o.trials == 0)
    throw InputError(file, "study.trials", "must be at least 1", "write the shard again");
  return o;
}

std::string writeStudyOutput(const std::filesystem::path& dir, const studies::StudyOutput& output) {
  for (const auto& [name, text] : output.files) io::writeTextAtomically(dir / name, text);
  return drawPlots(dir, output.gnuplot_scripts);
}

}  // namespace lidarcal::pipeline
