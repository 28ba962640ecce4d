// SPDX-License-Identifier: BSD-3-Clause
// change_test_level [--trials N] [--level A] [--absolute]: the watcher's change test
// (watch/shift_history.hpp), or with --absolute the baseline's test of the record against zero,
// on draws of its own model, s_k = b + u_k + e_k with u_k ~ N(0, tau^2 I) and
// e_k ~ N(0, phi^2 C_k): how often a check of the same law is rejected at level A, divided by A,
// by the record's length n, the spread tau and the scale phi (docs/results/watch.md). The record
// knows neither tau nor phi; the table shows what estimating them from n checks leaves of the
// level. Fixed seed: the table is reproducible.

#include <cmath>
#include <cstdio>
#include <random>

#include <CLI/CLI.hpp>
#include <Eigen/Cholesky>

#include "watch/shift_history.hpp"

namespace {

using lidarcal::watch::Shift;
using lidarcal::watch::ShiftHistory;

struct Law {
  double phi = 1.0, tau_m = 0.0;
  Eigen::Vector2d bias{0.003, -0.001};  ///< shared by every check; zero for the absolute test
};

/// Draws checks whose covariances vary as a drive's do: 0.5-3 mm per distance, correlation
/// -0.8..0.8, the fit's own bias 3 and -1 mm.
class Checks {
 public:
  explicit Checks(std::uint64_t seed) : rng_(seed) {}
  Shift draw(const Law& law) {
    const double a = 0.0005 + 0.0025 * unit_(rng_), c = 0.0005 + 0.0025 * unit_(rng_);
    const double rho = -0.8 + 1.6 * unit_(rng_);
    Shift s;
    s.c << a * a, rho * a * c, rho * a * c, c * c;
    const Eigen::Matrix2d l = s.c.llt().matrixL();
    s.s =
        law.bias + law.phi * l * Eigen::Vector2d(z(), z()) + law.tau_m * Eigen::Vector2d(z(), z());
    return s;
  }

 private:
  double z() { return normal_(rng_); }
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> unit_{0.0, 1.0};
};

/// The rejection rate over `trials` records of `n` checks, each followed by one more check
/// (change test), or of the record's mean against zero (absolute test, a model without error).
double rejected(const Law& law, int n, int trials, double level, std::uint64_t seed,
                bool absolute) {
  Checks checks(seed);
  int count = 0;
  for (int t = 0; t < trials; ++t) {
    ShiftHistory record(static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) record.add(checks.draw(law));
    const double p =
        absolute ? record.absolute(Eigen::Matrix2d::Zero()).p : record.change(checks.draw(law)).p;
    count += p < level ? 1 : 0;
  }
  return count / static_cast<double>(trials);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "The watcher's change test (or absolute test) on draws of its own model: rejections per "
      "level"};
  int trials = 20000;
  double level = 0.05;
  bool absolute = false;
  app.add_option("--trials", trials, "records per cell")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--level", level, "the test's level")
      ->capture_default_str()
      ->check(CLI::Range(1e-4, 0.5));
  app.add_flag("--absolute", absolute,
               "the baseline's absolute test instead: the record's mean against zero, checks "
               "without a shared bias");
  CLI11_PARSE(app, argc, argv);
  const int lengths[] = {5, 8, 20, 50};
  const double sd = std::sqrt(level * (1.0 - level) / trials) / level;
  std::printf(
      "%s test: rejected / level at level %g, %d records per cell (one binomial SD: %.3f)\n\n",
      absolute ? "Absolute" : "Change", level, trials, sd);
  std::printf("| φ | τ [mm] | n = 5 | n = 8 | n = 20 | n = 50 |\n|---|---|---|---|---|---|\n");
  std::uint64_t seed = 1;
  for (double phi : {0.6, 1.0, 1.7})
    for (double tau_mm : {0.0, 0.5, 1.0, 2.0}) {
      Law law{phi, tau_mm / 1000.0};
      if (absolute) law.bias.setZero();  // the model is right: the record's mean is zero
      std::printf("| %.1f | %.1f |", phi, tau_mm);
      for (int n : lengths)
        std::printf(" %.2f |", rejected(law, n, trials, level, seed++, absolute) / level);
      std::printf("\n");
      std::fflush(stdout);
    }
}
