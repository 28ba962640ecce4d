// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/noise_run.hpp"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "io/atomic_file.hpp"
#include "io/gnuplot.hpp"
#include "io/noise_json.hpp"

namespace lidarcal::pipeline {
namespace {

using ojson = nlohmann::ordered_json;

/// Names and traces of the plotted parameters: best point per evaluation (kl-hill) or
/// variances per iteration (ml).
struct ParameterTraces {
  std::vector<std::string> names;
  std::vector<std::vector<double>> rows;  // one row per x value
};

ParameterTraces parameterTraces(const NoiseRun& run, int sensors) {
  ParameterTraces t;
  if (run.kl) {
    t.names = run.kl->parameter_names;
    for (const auto& rec : run.kl->climb.trace) t.rows.push_back(rec.best_params);
  } else if (run.ml) {
    for (int s = 0; s < sensors; ++s) {
      t.names.push_back("s" + std::to_string(s) + ".range_var_m2");
      t.names.push_back("s" + std::to_string(s) + ".bearing_var_rad2");
    }
    for (const char* n : {"process.dx_m2", "process.dy_m2", "process.dtheta_rad2"})
      t.names.push_back(n);
    t.rows = run.ml->variance_trace;
  }
  return t;
}

/// Value of parameter `name` (as in ParameterTraces) in a setting; NaN when unknown.
double valueOf(const NoiseSetting& n, const std::string& name) {
  if (name.rfind("process.", 0) == 0) {
    if (name == "process.dx_m2") return n.process.dx_var_m2;
    if (name == "process.dy_m2") return n.process.dy_var_m2;
    return n.process.dtheta_var_rad2;
  }
  const std::size_t dot = name.find('.');
  const auto s = static_cast<std::size_t>(std::stoi(name.substr(1, dot - 1)));
  if (s >= n.sensors.size()) return std::nan("");
  const SensorNoise& sn = n.sensors[s];
  const std::string field = name.substr(dot + 1);
  if (field == "range_mean_m") return sn.range_mean_m;
  if (field == "range_var_m2") return sn.range_var_m2;
  if (field == "bearing_mean_rad") return sn.bearing_mean_rad;
  return sn.bearing_var_rad2;
}

}  // namespace

NoiseSetting defaultInitialNoise(int sensors) {
  NoiseSetting n;
  n.sensors.assign(static_cast<std::size_t>(sensors), SensorNoise{0.0, 0.5, 0.0, 0.5});
  return n;
}

NoiseRun runNoiseEstimation(const noise::NoiseProblem& problem, const NoiseRunOptions& options,
                            const std::function<void(std::size_t, std::size_t)>& on_progress) {
  NoiseRun run;
  run.method = options.method;
  run.faithful = options.faithful;
  run.seed = options.seed;
  const auto t0 = std::chrono::steady_clock::now();
  if (options.method == NoiseMethod::kl_hill) {
    const noise::KlHillConfig& config = options.kl;
    const NoiseSetting initial =
        options.initial ? *options.initial : defaultInitialNoise(problem.sensors);
    const auto total = static_cast<std::size_t>(config.climb.max_evaluations);
    run.kl =
        noise::estimateNoiseKlHill(problem, initial, config, options.seed, [&](int done, double) {
          if (on_progress) on_progress(static_cast<std::size_t>(done), total);
        });
    run.noise = run.kl->noise;
    run.process_estimated = config.climb_process;
    for (const auto& rec : run.kl->climb.trace) run.objective_trace.push_back(rec.best_value);
    run.evaluations = run.kl->climb.evaluations;
    if (!run.kl->climb.converged) {
      run.status = "not_converged";
      run.message =
          "stopped at the evaluation cap (" + std::to_string(config.climb.max_evaluations) + ")";
    }
  } else {
    noise::MlNoiseConfig config = options.ml;
    if (options.initial) config.initial = *options.initial;
    run.ml = noise::estimateNoiseMl(problem, config);
    if (on_progress)
      on_progress(static_cast<std::size_t>(run.ml->iterations),
                  static_cast<std::size_t>(run.ml->iterations));
    run.noise = run.ml->noise;
    run.process_estimated = config.estimate_process;
    run.objective_trace = run.ml->objective_trace;
    run.evaluations = run.ml->iterations;
    if (!run.ml->converged) {
      run.status = "not_converged";
      run.message = run.ml->message;
    }
  }
  run.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return run;
}

ojson noiseRunToJson(const NoiseRun& run, const noise::NoiseProblem& problem,
                     const std::vector<int>& sensor_labels) {
  auto label = [&](std::size_t s) {
    return s < sensor_labels.size() ? sensor_labels[s] : static_cast<int>(s);
  };
  ojson j{{"format", "lidarcal-noise-result/1"},
          {"method", run.method == NoiseMethod::kl_hill ? "kl-hill" : "ml"}};
  if (run.method == NoiseMethod::kl_hill) {
    j["variant"] = run.faithful ? "faithful" : "sound";
    j["seed"] = run.seed;
  }
  j["status"] = run.status;
  j["message"] = run.message;
  const ojson setting = io::noiseSettingToJson(run.noise);
  j["sensors"] = setting["sensors"];
  for (std::size_t s = 0; s < j["sensors"].size(); ++s) j["sensors"][s]["sensor"] = label(s);
  if (run.ml)
    for (std::size_t s = 0; s < j["sensors"].size(); ++s) {
      const auto& g = run.ml->groups;
      auto& e = j["sensors"][s];
      e["range_mean_se_m"] = run.ml->bias_standard_error[2 * s];
      e["range_var_se_m2"] = g[2 * s].standard_error;
      e["bearing_mean_se_rad"] = run.ml->bias_standard_error[2 * s + 1];
      e["bearing_var_se_rad2"] = g[2 * s + 1].standard_error;
    }
  j["process_var"] = setting["process_var"];
  j["process_var_estimated"] = run.process_estimated;
  j["objective"] = run.method == NoiseMethod::kl_hill ? "kl_total_nats" : "neg_log_likelihood_nats";
  j["objective_trace"] = run.objective_trace;
  j["evaluations"] = run.evaluations;
  j["data"] = ojson{{"stops", problem.stops},
                    {"sensors", problem.sensors},
                    {"landmarks", problem.landmarks},
                    {"observations", problem.observations.size()},
                    {"skipped_unassociated", problem.skipped_unassociated}};
  if (run.kl) {
    const auto& k = *run.kl;
    ojson at_best = ojson::array();
    for (std::size_t s = 0; s < k.at_best.kl_range.size(); ++s)
      at_best.push_back(ojson{{"sensor", label(s)},
                              {"predicted_range_mean_m", k.at_best.predicted_range[s].mean},
                              {"predicted_range_var_m2", k.at_best.predicted_range[s].var},
                              {"predicted_bearing_mean_rad", k.at_best.predicted_bearing[s].mean},
                              {"predicted_bearing_var_rad2", k.at_best.predicted_bearing[s].var},
                              {"kl_range_nats", k.at_best.kl_range[s]},
                              {"kl_bearing_nats", k.at_best.kl_bearing[s]}});
    std::vector<double> values;
    for (const auto& rec : k.climb.trace) values.push_back(rec.value);
    j["kl_hill"] = ojson{{"parameters", k.parameter_names},
                         {"best_objective", k.climb.best_value},
                         {"objective_values", values},
                         {"sweeps", k.climb.sweeps},
                         {"jumps", k.climb.jumps},
                         {"converged", k.climb.converged},
                         {"at_best", at_best}};
  }
  if (run.ml) {
    ojson groups = ojson::array();
    for (const auto& g : run.ml->groups)
      groups.push_back(ojson{{"name", g.name},
                             {"count", g.count},
                             {"redundancy", g.redundancy},
                             {"sum_sq", g.sum_sq},
                             {"variance", g.variance},
                             {"standard_error", g.standard_error},
                             {"at_floor", g.at_floor}});
    j["ml"] = ojson{{"converged", run.ml->converged},
                    {"iterations", run.ml->iterations},
                    {"solver_iterations", run.ml->solver_iterations},
                    {"standard_error_method", run.ml->standard_error_method},
                    {"groups", groups}};
  }
  return j;
}

namespace {

/// trace.dat: the objective per evaluation (kl-hill, with the best so far) or iteration (ML).
void writeTrace(const std::filesystem::path& dir, const NoiseRun& run, bool kl) {
  std::ostringstream o;
  o.precision(12);
  o << "# " << (kl ? "evaluation value best_value" : "iteration neg_log_likelihood") << "\n";
  for (std::size_t i = 0; i < run.objective_trace.size(); ++i) {
    o << i + 1;
    if (kl) o << ' ' << run.kl->climb.trace[i].value;
    o << ' ' << run.objective_trace[i] << '\n';
  }
  io::writeTextAtomically(dir / "trace.dat", o.str());
}

/// params.dat: the parameters per evaluation or iteration.
void writeParameters(const std::filesystem::path& dir, const ParameterTraces& params, bool kl) {
  std::ostringstream o;
  o.precision(12);
  o << "# " << (kl ? "evaluation" : "iteration");
  for (const auto& n : params.names) o << ' ' << n;
  o << '\n';
  for (std::size_t i = 0; i < params.rows.size(); ++i) {
    o << i + 1;
    for (double v : params.rows[i]) o << ' ' << v;
    o << '\n';
  }
  io::writeTextAtomically(dir / "params.dat", o.str());
}

/// The objective's plot.
void objectivePlot(std::ostringstream& gp, const std::filesystem::path& dir, const NoiseRun& run,
                   bool kl) {
  gp << "set output " << io::gnuplotString((dir / "objective.png").string()) << "\n";
  if (kl) {
    gp << "set title "
       << io::gnuplotString(std::string("KL noise consistency (") +
                            (run.faithful ? "published variant" : "our variant") + "), seed " +
                            std::to_string(run.seed))
       << "\n";
    gp << "set ylabel \"total KL divergence (nats)\"\nset logscale y\n";
    gp << "plot " << io::gnuplotString((dir / "trace.dat").string())
       << " using 1:2 with points pt 7 ps 0.4 lc rgb \"#999999\" title \"evaluated\", \\\n"
       << "     '' using 1:3 with steps lw 2 lc rgb \"#c00000\" title \"best so far\"\n";
  } else {
    gp << "set title \"ML (VCE): negative log-likelihood per iteration\"\nset ylabel \"-log L "
          "(nats, constants dropped)\"\n";
    gp << "plot " << io::gnuplotString((dir / "trace.dat").string())
       << " using 1:2 with linespoints lw 2 title \"-log L\"\n";
  }
  gp << "unset logscale y\nunset title\n";
}

/// The parameters' plot: variances on top, means below (kl-hill with climbed means); the truth
/// dashed when known.
void parameterPlot(std::ostringstream& gp, const std::filesystem::path& dir,
                   const ParameterTraces& params, const std::optional<NoiseSetting>& truth,
                   bool kl) {
  std::vector<std::size_t> vars, means;
  for (std::size_t i = 0; i < params.names.size(); ++i)
    (params.names[i].find("_mean_") != std::string::npos ? means : vars).push_back(i);
  const int panels = means.empty() ? 1 : 2;
  gp << "set output " << io::gnuplotString((dir / "params.png").string()) << "\n";
  gp << "set multiplot layout " << panels << ",1 title "
     << io::gnuplotString(std::string(kl ? "best parameters so far" : "variance components") +
                          (truth ? " (dashed: truth)" : ""))
     << "\n";
  auto panel = [&](const std::vector<std::size_t>& idx, const std::string& ylabel) {
    gp << "set ylabel " << io::gnuplotString(ylabel) << "\nset title "
       << io::gnuplotString(ylabel.substr(0, ylabel.find(' ')) + "s") << "\nplot ";
    for (std::size_t n = 0; n < idx.size(); ++n) {
      const std::size_t i = idx[n];
      gp << (n ? ", \\\n     " : "") << io::gnuplotString((dir / "params.dat").string())
         << " using 1:" << i + 2 << " with steps lw 2 lc " << n + 1 << " title "
         << io::gnuplotString(params.names[i]);
      if (truth) {
        const double t = valueOf(*truth, params.names[i]);
        if (std::isfinite(t)) gp << ", " << t << " with lines dt 2 lc " << n + 1 << " notitle";
      }
    }
    gp << "\n";
  };
  panel(vars, "variance (m^2 or rad^2)");
  if (!means.empty()) panel(means, "mean (m or rad)");
  gp << "unset multiplot\n";
}

}  // namespace

std::string writeNoisePlots(const std::filesystem::path& dir, const NoiseRun& run,
                            const std::optional<NoiseSetting>& truth) {
  const bool kl = run.method == NoiseMethod::kl_hill;
  writeTrace(dir, run, kl);
  const ParameterTraces params = parameterTraces(run, static_cast<int>(run.noise.sensors.size()));
  writeParameters(dir, params, kl);
  std::ostringstream gp;
  gp << "set terminal pngcairo size 1000,700 noenhanced\nset grid\nset key outside right\n";
  gp << "set xlabel " << io::gnuplotString(kl ? "objective evaluation" : "VCE iteration") << "\n";
  objectivePlot(gp, dir, run, kl);
  parameterPlot(gp, dir, params, truth, kl);
  io::writeTextAtomically(dir / "plot.gp", gp.str());
  std::string why;
  return io::runGnuplot(dir, "plot.gp", &why) ? std::string() : why;
}

}  // namespace lidarcal::pipeline
