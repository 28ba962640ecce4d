// SPDX-License-Identifier: BSD-3-Clause
// Long inputs: peak memory and time of `lidarcal detect` and `lidarcal correct` on sequences of
// 1,000 to 100,000 scans (docs/results/hardening.md). Each command runs in a child process
// whose own peak resident memory is read with wait4 (child_process.hpp).
//
// The sequences are the bundled example (10 stops x 10 scans of the paper's field, 4.4 KB per
// scan) repeated: scan i is a hard link to example scan i mod 100, so a 100,000-scan sequence
// has 10,000 stops of 10 scans, costs no disk and every scan is a real one with five poles to
// detect. The outputs (up to 0.6 GB at 100,000 scans) are deleted after each step.
//
//   long_sequence [--sizes 1000,10000,100000] [--work DIR] [--lidarcal PATH] > table.md

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "child_process.hpp"

namespace {

namespace fs = std::filesystem;
using lidarcal::bench::Measure;
using lidarcal::bench::runChild;

std::string scanName(std::size_t i) {
  char name[32];
  std::snprintf(name, sizeof name, "scan_%06zu.pcd", i);
  return name;
}

/// A sequence of n scans made of hard links to the example's 100.
void linkSequence(const fs::path& example, const fs::path& dir, std::size_t n) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file(example / "sequence.json", dir / "sequence.json");
  for (std::size_t i = 0; i < n; ++i)
    fs::create_hard_link(example / scanName(i % 100), dir / scanName(i));
}

double mib(long kib) { return static_cast<double>(kib) / 1024.0; }

Measure mustRun(const std::string& exe, const std::vector<std::string>& args) {
  const Measure m = runChild(exe, args);
  if (m.exit_code != 0) {
    std::fprintf(stderr, "long_sequence: `lidarcal %s ...` failed with exit code %d\n",
                 args.front().c_str(), m.exit_code);
    std::exit(1);
  }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::size_t> sizes = {1000, 10000, 100000};
  fs::path work = fs::temp_directory_path() / ("lidarcal-long-" + std::to_string(::getpid()));
  std::string exe = LIDARCAL_EXE;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--sizes") {
      sizes.clear();
      std::stringstream in(value);
      for (std::string item; std::getline(in, item, ',');) sizes.push_back(std::stoul(item));
    } else if (key == "--work") {
      work = value;
    } else if (key == "--lidarcal") {
      exe = value;
    } else {
      std::fprintf(
          stderr,
          "usage: long_sequence [--sizes 1000,10000,100000] [--work DIR] [--lidarcal PATH]\n");
      return 2;
    }
  }
  const fs::path example = fs::path(LIDARCAL_SOURCE_DIR) / "data/example/scans";
  fs::create_directories(work);
  const fs::path model = work / "model.json";
  mustRun(exe, {"calibrate", "-q", example.string(), "--out", model.string(), "--overwrite"});
  const Measure base = mustRun(exe, {"--version"});

  std::printf(
      "| scans | stops | `detect` peak RSS (MiB) | `detect` wall (s) | `correct` peak RSS (MiB) | "
      "`correct` wall (s) |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|\n");
  for (std::size_t n : sizes) {
    const fs::path seq = work / "seq";
    linkSequence(example, seq, n);
    const fs::path out = work / "out";
    fs::remove_all(out);
    const Measure d = mustRun(exe, {"detect", "-q", seq.string(), "--out", out.string()});
    fs::remove_all(out);
    const Measure c = mustRun(
        exe, {"correct", "-q", seq.string(), "--model", model.string(), "--out", out.string()});
    fs::remove_all(out);
    fs::remove_all(seq);
    std::printf("| %zu | %zu | %.1f | %.1f | %.1f | %.1f |\n", n, n / 10, mib(d.max_rss_kib),
                d.wall_s, mib(c.max_rss_kib), c.wall_s);
    std::fflush(stdout);
  }
  std::printf("\nBaseline: `lidarcal --version` peaks at %.1f MiB (the libraries loaded).\n",
              mib(base.max_rss_kib));
  fs::remove_all(work);
  return 0;
}
