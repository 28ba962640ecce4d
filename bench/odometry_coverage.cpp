// SPDX-License-Identifier: BSD-3-Clause
// odometry_coverage [--drives N] [--samples S]: how often the 95 % intervals of
// `lidarcal odometry` hold the truth on simulated drives (docs/results/odometry.md), for the
// covariance without trimming, with the published trimming, and with scan-matching failures.
// Prints one Markdown table; the seeds are fixed (1000, 1001, ...), so the table is reproducible.

#include <cmath>
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "odometry/calibrate.hpp"
#include "odometry/simulated_samples.hpp"

namespace {

using namespace lidarcal::odometry;

struct Case {
  const char* name;
  int rounds;
  double outlier_fraction;
};

void row(const Case& c, int drives, std::size_t samples) {
  Vector6 covered = Vector6::Zero(), z2 = Vector6::Zero();
  int failed = 0;
  OdometrySettings method;
  method.trimming_rounds = c.rounds;
  for (int d = 0; d < drives; ++d) {
    SimulationSettings s;
    s.samples = samples;
    s.outlier_fraction = c.outlier_fraction;
    s.seed = 1000 + static_cast<std::uint64_t>(d);
    const OdometryResult r = calibrateOdometry(simulateSamples(s), method);
    if (!r.ok()) {
      ++failed;
      continue;
    }
    const Vector6 z =
        (r.estimate.toVector() - s.truth.toVector()).cwiseQuotient(r.standardErrors());
    for (int k = 0; k < kParameterCount; ++k) covered[k] += std::abs(z[k]) <= 1.959964 ? 1 : 0;
    z2 += z.cwiseAbs2();
  }
  const double n = drives - failed;
  std::printf("| %s |", c.name);
  for (int k = 0; k < kParameterCount; ++k)
    std::printf(" %.1f %% (%.2f) |", 100.0 * covered[k] / n, std::sqrt(z2[k] / n));
  std::printf(" %d |\n", failed);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Coverage of lidarcal odometry's 95 % intervals on simulated drives"};
  int drives = 1000;
  std::size_t samples = 600;
  app.add_option("--drives", drives, "simulated drives per row")->capture_default_str();
  app.add_option("--samples", samples, "samples (intervals) per drive")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::printf("| method | r_L | r_R | b | l_x | l_y | l_theta | failed |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  const Case cases[] = {{"no trimming", 0, 0.0},
                        {"published: 4 rounds at the 99th percentile", 4, 0.0},
                        {"published, 3 % scan-matching failures", 4, 0.03}};
  for (const Case& c : cases) row(c, drives, samples);
  return 0;
}
