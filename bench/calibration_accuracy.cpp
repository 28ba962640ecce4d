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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Calibration accuracy: calibrate on one simulated sequence, evaluate on another"};
  std::string scene, work = "/tmp/lidarcal-accuracy";
  int seeds = 20, first = 1;
  double sigma_s = 0.02, sigma_psi = 0.5;
  app.add_option("--scene", scene, "Scene file")->required();
  app.add_option("--seeds", seeds, "Number of seeds")->capture_default_str();
  app.add_option("--first-seed", first, "First seed")->capture_default_str();
  app.add_option("--sigma-s", sigma_s, "Prior on stop positions given to calibrate (m)")
      ->capture_default_str();
  app.add_option("--sigma-psi", sigma_psi, "Prior on stop headings given to calibrate (deg)")
      ->capture_default_str();
  app.add_option("--work", work, "Scratch directory (replaced)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const std::string exe = LIDARCAL_EXE;
  fs::remove_all(work);
  fs::create_directories(work);
  const std::vector<std::string> names = {"joint", "closed-form", "oracle", "oracle-commanded"};
  std::map<std::string, std::vector<double>> ratio;
  std::map<std::string, std::vector<int>> order;
  std::vector<double> joint_over_bound, joint_over_cf, joint_over_oracle;
  const std::string priors =
      " --sigma-s " + std::to_string(sigma_s) + " --sigma-psi " + std::to_string(sigma_psi);
  for (int s = first; s < first + seeds; ++s) {
    const fs::path dir = fs::path(work) / std::to_string(s);
    const fs::path cal = dir / "cal", ev = dir / "eval";
    fs::create_directories(dir);
    sh(exe + " simulate -q --scene " + scene + " --out " + cal.string() + " --seed " +
       std::to_string(s));
    sh(exe + " simulate -q --scene " + scene + " --out " + ev.string() + " --seed " +
       std::to_string(100000 + s));
    std::map<std::string, double> r;
    for (const auto& n : names) {
      const fs::path model = dir / (n + ".json");
      std::string cmd =
          exe + " calibrate -q " + (cal / "scans").string() + " --out " + model.string() + priors;
      if (n == "joint" || n == "closed-form")
        cmd += " --method " + n;
      else
        cmd += " --truth " + (cal / "truth.json").string() +
               (n == "oracle" ? "" : " --frame commanded");
      sh(cmd);
      const fs::path out = dir / ("corrected-" + n);
      sh(exe + " correct -q " + (ev / "scans").string() + " --model " + model.string() + " --out " +
         out.string());
      sh(exe + " evaluate " + out.string() + " --truth " + (ev / "truth.json").string() +
         " --out " + (dir / (n + "-eval.json")).string());
      r[n] = readJson(dir / (n + "-eval.json"))["landmarks"]["mse_ratio"].get<double>();
      ratio[n].push_back(r[n]);
      order[n].push_back(readJson(model)["bias"]["order"].get<int>());
    }
    joint_over_bound.push_back(r["joint"] / r["oracle-commanded"]);
    joint_over_cf.push_back(r["joint"] / r["closed-form"]);
    joint_over_oracle.push_back(r["joint"] / r["oracle"]);
    std::fprintf(
        stderr, "seed %d: joint %.1f  closed form %.1f  oracle %.1f  commanded-frame oracle %.1f\n",
        s, r["joint"], r["closed-form"], r["oracle"], r["oracle-commanded"]);
    fs::remove_all(dir);
  }

  std::printf(
      "Scene `%s`, %d seeds (%d..%d); calibration sequence seed s, evaluation sequence seed 100000 "
      "+ s.\n\n",
      scene.c_str(), seeds, first, first + seeds - 1);
  std::printf(
      "| model | MSE ratio on landmark returns: median | quartiles | order 2 chosen "
      "|\n|---|---|---|---|\n");
  for (const auto& n : names) {
    const auto& v = ratio[n];
    const auto twos = std::count(order[n].begin(), order[n].end(), 2);
    std::printf("| %s | %.1f | %.1f - %.1f | %ld / %zu |\n", n.c_str(), quantile(v, 0.5),
                quantile(v, 0.25), quantile(v, 0.75), static_cast<long>(twos), v.size());
  }
  std::printf("\n| ratio of MSE ratios, per seed | median | quartiles |\n|---|---|---|\n");
  std::printf("| joint / commanded-frame oracle (the bound) | %.2f | %.2f - %.2f |\n",
              quantile(joint_over_bound, 0.5), quantile(joint_over_bound, 0.25),
              quantile(joint_over_bound, 0.75));
  std::printf("| joint / oracle | %.2f | %.2f - %.2f |\n", quantile(joint_over_oracle, 0.5),
              quantile(joint_over_oracle, 0.25), quantile(joint_over_oracle, 0.75));
  std::printf("| joint / closed form | %.1f | %.1f - %.1f |\n", quantile(joint_over_cf, 0.5),
              quantile(joint_over_cf, 0.25), quantile(joint_over_cf, 0.75));
  return 0;
}
