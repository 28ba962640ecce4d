// SPDX-License-Identifier: BSD-3-Clause
// Calibration accuracy through the command line, as a user would run it
// (docs/results/calibration-accuracy.md): for each seed, simulate a calibration sequence and an
// evaluation sequence of the same scene, calibrate on the first (joint, closed form, oracle,
// oracle in the commanded frame), correct the second with each model and evaluate it against
// its truth.
//
//   build/bench/calibration_accuracy --scene data/scenes/paper_field.json --seeds 20
//       [--sigma-s 0.02 --sigma-psi 0.5] [--work /tmp/acc]

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

void sh(const std::string& cmd) {
  if (std::system((cmd + " >/dev/null").c_str()) != 0) {
    std::fprintf(stderr, "failed: %s\n", cmd.c_str());
    std::exit(1);
  }
}

nlohmann::json readJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

struct Options {
  std::string scene, work = "/tmp/lidarcal-accuracy";
  int seeds = 20, first = 1;
  double sigma_s = 0.02, sigma_psi = 0.5;  ///< priors given to calibrate: metres, degrees
};

/// The models compared: calibrate's two methods and the oracle in both frames.
const std::vector<std::string> kModels = {"joint", "closed-form", "oracle", "oracle-commanded"};

/// Per model the MSE ratios and chosen orders over the seeds; per seed the joint refinement's
/// ratio over the others'.
struct Results {
  std::map<std::string, std::vector<double>> ratio;
  std::map<std::string, std::vector<int>> order;
  std::vector<double> joint_over_bound, joint_over_cf, joint_over_oracle;
};

/// Seed `s`: simulates both sequences, calibrates on the first with each model, corrects and
/// evaluates the second.
void runSeed(const Options& o, int s, Results& res) {
  const std::string exe = LIDARCAL_EXE;
  const std::string priors =
      " --sigma-s " + std::to_string(o.sigma_s) + " --sigma-psi " + std::to_string(o.sigma_psi);
  const fs::path dir = fs::path(o.work) / std::to_string(s);
  const fs::path cal = dir / "cal", ev = dir / "eval";
  fs::create_directories(dir);
  sh(exe + " simulate -q --scene " + o.scene + " --out " + cal.string() + " --seed " +
     std::to_string(s));
  sh(exe + " simulate -q --scene " + o.scene + " --out " + ev.string() + " --seed " +
     std::to_string(100000 + s));
  std::map<std::string, double> r;
  for (const auto& n : kModels) {
    const fs::path model = dir / (n + ".json");
    std::string cmd =
        exe + " calibrate -q " + (cal / "scans").string() + " --out " + model.string() + priors;
    if (n == "joint" || n == "closed-form")
      cmd += " --method " + n;
    else
      cmd +=
          " --truth " + (cal / "truth.json").string() + (n == "oracle" ? "" : " --frame commanded");
    sh(cmd);
    const fs::path out = dir / ("corrected-" + n);
    sh(exe + " correct -q " + (ev / "scans").string() + " --model " + model.string() + " --out " +
       out.string());
    sh(exe + " evaluate " + out.string() + " --truth " + (ev / "truth.json").string() + " --out " +
       (dir / (n + "-eval.json")).string());
    r[n] = readJson(dir / (n + "-eval.json"))["landmarks"]["mse_ratio"].get<double>();
    res.ratio[n].push_back(r[n]);
    res.order[n].push_back(readJson(model)["bias"]["order"].get<int>());
  }
  res.joint_over_bound.push_back(r["joint"] / r["oracle-commanded"]);
  res.joint_over_cf.push_back(r["joint"] / r["closed-form"]);
  res.joint_over_oracle.push_back(r["joint"] / r["oracle"]);
  std::fprintf(stderr,
               "seed %d: joint %.1f  closed form %.1f  oracle %.1f  commanded-frame oracle %.1f\n",
               s, r["joint"], r["closed-form"], r["oracle"], r["oracle-commanded"]);
  fs::remove_all(dir);
}

void printTables(const Options& o, Results& res) {
  std::printf(
      "Scene `%s`, %d seeds (%d..%d); calibration sequence seed s, evaluation sequence seed 100000 "
      "+ s.\n\n",
      o.scene.c_str(), o.seeds, o.first, o.first + o.seeds - 1);
  std::printf(
      "| model | MSE ratio on landmark returns: median | quartiles | order 2 chosen "
      "|\n|---|---|---|---|\n");
  for (const auto& n : kModels) {
    const auto& v = res.ratio[n];
    const auto twos = std::count(res.order[n].begin(), res.order[n].end(), 2);
    std::printf("| %s | %.1f | %.1f - %.1f | %ld / %zu |\n", n.c_str(), quantile(v, 0.5),
                quantile(v, 0.25), quantile(v, 0.75), static_cast<long>(twos), v.size());
  }
  const auto& bound = res.joint_over_bound;
  const auto& oracle = res.joint_over_oracle;
  const auto& cf = res.joint_over_cf;
  std::printf("\n| ratio of MSE ratios, per seed | median | quartiles |\n|---|---|---|\n");
  std::printf("| joint / commanded-frame oracle (the bound) | %.2f | %.2f - %.2f |\n",
              quantile(bound, 0.5), quantile(bound, 0.25), quantile(bound, 0.75));
  std::printf("| joint / oracle | %.2f | %.2f - %.2f |\n", quantile(oracle, 0.5),
              quantile(oracle, 0.25), quantile(oracle, 0.75));
  std::printf("| joint / closed form | %.1f | %.1f - %.1f |\n", quantile(cf, 0.5),
              quantile(cf, 0.25), quantile(cf, 0.75));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Calibration accuracy: calibrate on one simulated sequence, evaluate on another"};
  Options o;
  app.add_option("--scene", o.scene, "Scene file")->required();
  app.add_option("--seeds", o.seeds, "Number of seeds")->capture_default_str();
  app.add_option("--first-seed", o.first, "First seed")->capture_default_str();
  app.add_option("--sigma-s", o.sigma_s, "Prior on stop positions given to calibrate (m)")
      ->capture_default_str();
  app.add_option("--sigma-psi", o.sigma_psi, "Prior on stop headings given to calibrate (deg)")
      ->capture_default_str();
  app.add_option("--work", o.work, "Scratch directory (replaced)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  fs::remove_all(o.work);
  fs::create_directories(o.work);
  Results res;
  for (int s = o.first; s < o.first + o.seeds; ++s) runSeed(o, s, res);
  printTables(o, res);
  return 0;
}
