// SPDX-License-Identifier: BSD-3-Clause
// Import throughput and peak memory, measured on whole `lidarcal` processes: every step runs
// the installed-style command line in a child process (fork + exec) and reads the child's own
// resource usage (wait4: ru_maxrss = peak resident memory, and wall time around it). Steps with
// fewer scans of the same recording show whether memory grows with the number of scans; the
// `lidarcal --version` step is the baseline footprint of the process (PCL, ROS libraries loaded).
//
//   bench_import [--repeat N] [--data DIR] [--lidarcal PATH] > table.md
//
// Times are medians over N runs (default 5), peak RSS the largest.
//
// Add a step by appending to steps(); a step with `keep` writes to that directory and leaves it
// for later steps (the detect step reads the kept Freiburg import). Numbers: docs/results/speed.md.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "child_process.hpp"

namespace {

namespace fs = std::filesystem;

struct Step {
  std::string name;  // shown in the table
  // arguments of `lidarcal` ({OUT} is replaced by the step's output directory)
  std::vector<std::string> args;
  std::size_t scans = 0;  // scans processed (for scans/s); 0 = not a per-scan step
  std::string input;      // file that must exist (skipped otherwise)
  int repeat = 0;         // runs of this step; 0 = --repeat
  // if set: write here instead of a scratch directory, and keep it for later steps
  std::string keep;
};

using lidarcal::bench::Measure;
using lidarcal::bench::runChild;

/// Four copies of the Freiburg 079 log back to back (gzip members may be concatenated): a
/// 19,164-scan recording, to show that memory does not grow with the length of the input.
std::string longLog(const fs::path& data, const fs::path& work) {
  const fs::path source = data / "carmen/freiburg-079-corrected.log.gz";
  const fs::path target = work / "freiburg-079-x4.log.gz";
  if (!fs::exists(source)) return source.string();
  std::ifstream in(source, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream out(target, std::ios::binary);
  for (int i = 0; i < 4; ++i) out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return target.string();
}

std::vector<Step> steps(const fs::path& data, const fs::path& work) {
  const std::string freiburg = (data / "carmen/freiburg-079-corrected.log.gz").string();
  const std::string freiburg_x4 = longLog(data, work);
  const std::string bag = (data / "rplidar_a2_room/rplidar_1.bag").string();
  const std::vector<std::string> carmen = {"import", "-q",    "--from", "carmen",
                                           freiburg, "--out", "{OUT}"};
  const std::vector<std::string> rosbag = {"import", "-q",    "--from", "rosbag1",
                                           bag,      "--out", "{OUT}"};
  auto with = [](std::vector<std::string> v, std::initializer_list<std::string> extra) {
    v.insert(v.end(), extra);
    return v;
  };
  auto step = [](std::string name, std::vector<std::string> args, std::size_t scans,
                 std::string input, int repeat = 0, std::string keep = {}) {
    return Step{std::move(name), std::move(args), scans, std::move(input), repeat, std::move(keep)};
  };
  return {
      step("baseline: `lidarcal --version`", {"--version"}, 0, ""),
      step("import Freiburg 079 (CARMEN .log.gz), first 500 scans",
           with(carmen, {"--max-scans", "500"}), 500, freiburg),
      step("import Freiburg 079 (CARMEN .log.gz), all scans", carmen, 4791, freiburg),
      step("import Freiburg 079 four times over (19,164 scans, one run)",
           {"import", "-q", "--from", "carmen", freiburg_x4, "--out", "{OUT}"}, 4 * 4791,
           freiburg_x4, 1),
      step("import RPLIDAR bag (ROS1), first 130 scans", with(rosbag, {"--max-scans", "130"}), 130,
           bag),
      step("import RPLIDAR bag (ROS1), all scans", rosbag, 1319, bag),
      // Import + detect over Freiburg 079: the import is kept and the detector reads it back
      // (poles are not expected in that building; the point is speed and bounded memory).
      step("import Freiburg 079, first 500 scans (kept for detect)",
           with(carmen, {"--max-scans", "500"}), 500, freiburg, 1,
           (work / "freiburg079-500").string()),
      step("detect over the first 500 scans of Freiburg 079",
           {"detect", "-q", (work / "freiburg079-500").string(), "--out", "{OUT}"}, 500,
           (work / "freiburg079-500").string()),
      step("import Freiburg 079 again (kept for detect)", carmen, 4791, freiburg, 1,
           (work / "freiburg079").string()),
      step("detect over Freiburg 079 (4791 scans)",
           {"detect", "-q", (work / "freiburg079").string(), "--out", "{OUT}"}, 4791,
           (work / "freiburg079").string()),
  };
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 5;
  fs::path data = LIDARCAL_SHARED_DATA;
  std::string exe = LIDARCAL_EXE;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    if (key == "--repeat")
      repeat = std::max(1, std::atoi(argv[i + 1]));
    else if (key == "--data")
      data = argv[i + 1];
    else if (key == "--lidarcal")
      exe = argv[i + 1];
  }
  const fs::path work =
      fs::temp_directory_path() / ("lidarcal-bench-import-" + std::to_string(getpid()));
  fs::create_directories(work);

  // Wall time suffers when other work shares the CPU; the child's user and system CPU times much
  // less so. User time is lidarcal's own work; system time is mostly the file system creating
  // one file per scan.
  std::printf(
      "| step | scans | wall time | scans/s (wall) | user CPU | scans/s (user CPU) | system CPU | "
      "peak RSS |\n"
      "|---|---|---|---|---|---|---|---|\n");
  int failures = 0;
  int index = 0;
  for (const Step& step : steps(data, work)) {
    const fs::path out =
        step.keep.empty() ? work / ("step" + std::to_string(index++)) : fs::path(step.keep);
    if (!step.input.empty() && !fs::exists(step.input)) {
      std::printf("| %s | skipped: %s absent | | | |\n", step.name.c_str(), step.input.c_str());
      continue;
    }
    std::vector<std::string> args = step.args;
    for (auto& a : args)
      if (a == "{OUT}") a = out.string();
    std::vector<double> walls, users, systems;
    long rss = 0;
    const int runs = step.repeat > 0 ? step.repeat : repeat;
    for (int r = 0; r < runs; ++r) {
      fs::remove_all(out);  // each run writes a fresh sequence (not timed)
      const Measure m = runChild(exe, args);
      if (m.exit_code != 0) {
        std::fprintf(stderr, "bench_import: step '%s' exited with %d\n", step.name.c_str(),
                     m.exit_code);
        ++failures;
        break;
      }
      walls.push_back(m.wall_s);
      users.push_back(m.user_s);
      systems.push_back(m.system_s);
      rss = std::max(rss, m.max_rss_kib);
    }
    if (step.keep.empty()) fs::remove_all(out);
    if (walls.empty()) continue;
    const auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    const double wall = median(walls), user = median(users), sys = median(systems);
    const double mib = static_cast<double>(rss) / 1024.0;
    if (step.scans)
      std::printf("| %s | %zu | %.3f s | %.0f | %.3f s | %.0f | %.3f s | %.1f MiB |\n",
                  step.name.c_str(), step.scans, wall, static_cast<double>(step.scans) / wall, user,
                  static_cast<double>(step.scans) / user, sys, mib);
    else
      std::printf("| %s | | %.3f s | | %.3f s | | %.3f s | %.1f MiB |\n", step.name.c_str(), wall,
                  user, sys, mib);
  }
  fs::remove_all(work);
  return failures == 0 ? 0 : 1;
}
