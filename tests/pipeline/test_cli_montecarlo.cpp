// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal montecarlo` end to end: the files it promises, the same bytes with 1 and 2 threads,
// every plot drawn without the joint refinement, a failing plot that fails the command, refusals
// of bad options, and an interruption that leaves nothing behind.

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;
namespace fs = std::filesystem;

/// A small, fast study: 8 stops, 3 scans per stop, 4 trials of the quick grid.
const std::string kSmall =
    "montecarlo -q --quick --stops 8 --step 0.3 --scans-per-stop 3 --trials 4 --joint-trials 1 "
    "--seed 5";

TEST(CliMonteCarlo, WritesEveryFileAndTheCsvDoesNotDependOnTheThreadCount) {
  TempDir dir;
  const std::string a = (dir / "a").string(), b = (dir / "b").string();
  const auto r1 = runCli(kSmall + " --study fig10 --threads 1 --out " + a);
  ASSERT_EQ(r1.exit_code, 0) << r1.err;
  const auto r2 = runCli(kSmall + " --study fig10 --threads 2 --out " + b);
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  for (const char* f : {"fig10.csv", "fig10.gp", "fig10.md", "summary.md"}) {
    SCOPED_TRACE(f);
    ASSERT_TRUE(fs::exists(fs::path(a) / f));
    EXPECT_EQ(test::readFile(fs::path(a) / f), test::readFile(fs::path(b) / f));
  }
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    EXPECT_TRUE(fs::exists(fs::path(a) / "fig10.png"));
  }
  // One row per cell of the quick grid (3 sigma_s x 3 sigma_theta) under the header.
  const std::string csv = test::readFile(fs::path(a) / "fig10.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 10);
  EXPECT_EQ(csv.rfind("figure,level,", 0), 0u);
  // The existing output is refused without --overwrite.
  const auto again = runCli(kSmall + " --study fig10 --out " + a);
  EXPECT_NE(again.exit_code, 0);
}

bool haveGnuplot() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

TEST(CliMonteCarlo, WithoutTheJointRefinementEveryPlotIsDrawnFromWhatRan) {
  // --no-joint: no trial runs the joint refinement. A panel for it would have no point to draw
  // (gnuplot stops the whole figure there); the figures leave it out and every plot is drawn.
  if (!haveGnuplot()) GTEST_SKIP() << "gnuplot not installed";
  TempDir dir;
  const fs::path out = dir / "o";
  const auto r = runCli(kSmall + " --study all --no-joint --threads 2 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_EQ(r.out.find("Plots:"), std::string::npos) << r.out;  // nothing skipped or failed
  for (const char* fig : {"fig7", "fig8", "fig9", "fig10", "fig11"}) {
    SCOPED_TRACE(fig);
    EXPECT_TRUE(fs::exists(out / (std::string(fig) + ".png")));
    const std::string gp = test::readFile(out / (std::string(fig) + ".gp"));
    // No panel or series of an estimator that did not run.
    EXPECT_EQ(gp.find("title \"joint"), std::string::npos);
    EXPECT_EQ(gp.find(", joint refinement\""), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(out / "gnuplot.log"));
  // fig9: two rows (L = 2, 5) of two panels (closed form, oracle).
  EXPECT_NE(test::readFile(out / "fig9.gp").find("set multiplot layout 2,2"), std::string::npos);
}

/// The small study of fig10 into `out` with a stand-in `gnuplot` (a shell script of `body`, in
/// DIR/bin) first on the PATH.
test::CliResult withGnuplot(const TempDir& dir, const std::string& body, const fs::path& out) {
  const fs::path bin = dir / "bin";
  fs::create_directories(bin);
  test::writeFile(bin / "gnuplot", "#!/bin/sh\n" + body);
  fs::permissions(bin / "gnuplot", fs::perms::owner_all);
  return test::runCliPrefixed("export PATH='" + bin.string() + "':\"$PATH\"",
                              kSmall + " --study fig10 --out " + out.string());
}

TEST(CliMonteCarlo, APlotThatFailsFailsTheCommandAndWritesNothing) {
  // A gnuplot that fails on the script (here a stand-in on the PATH that starts, knows its
  // terminals and reports an error in the script) must not leave a successful run with a broken
  // figure behind: a bug of ours, exit 1.
  TempDir dir;
  const fs::path out = dir / "o";
  const auto r = withGnuplot(dir,
                             "[ \"$1\" = -e ] && exit 0\necho 'line 12: x range is invalid' >&2\n"
                             "exit 1\n",
                             out);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("gnuplot failed on fig10.gp"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("x range is invalid"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // No gnuplot at all: the study is written and the command says the plots were skipped.
  const fs::path empty = dir / "empty";
  fs::create_directories(empty);
  const fs::path out2 = dir / "o2";
  const auto r2 = test::runCliPrefixed("export PATH='" + empty.string() + "'",
                                       kSmall + " --study fig10 --out " + out2.string());
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_NE(r2.out.find("Plots: skipped, gnuplot is not installed"), std::string::npos) << r2.out;
  EXPECT_TRUE(fs::exists(out2 / "fig10.csv"));
  EXPECT_FALSE(fs::exists(out2 / "fig10.png"));
}

TEST(CliMonteCarlo, AGnuplotThatCannotDrawIsRefusedNamingItsPackage) {
  // Installed but broken (a library missing, or built without the cairo terminals): the machine
  // lacks something, not a bug of ours. Exit 2, the package named, nothing written.
  TempDir dir;
  const fs::path out = dir / "o";
  const auto r = withGnuplot(
      dir, "echo 'gnuplot: error while loading shared libraries: libcairo.so.2' >&2\nexit 127\n",
      out);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("apt-get install gnuplot-nox"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("libcairo.so.2"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliMonteCarlo, RefusesBadOptions) {
  TempDir dir;
  const std::string out = (dir / "o").string();
  EXPECT_EQ(runCli("montecarlo --study fig12 --out " + out).exit_code, 2);
  EXPECT_EQ(runCli("montecarlo --level photons --out " + out).exit_code, 2);
  EXPECT_EQ(runCli("montecarlo --level scan --angle-noise bearing --out " + out).exit_code, 2);
  EXPECT_EQ(runCli("montecarlo --angle-noise wobble --out " + out).exit_code, 2);
  EXPECT_EQ(runCli("montecarlo --noise-law cubic --out " + out).exit_code, 2);
  EXPECT_EQ(runCli("montecarlo --trials 0 --out " + out).exit_code, 2);
  EXPECT_FALSE(fs::exists(out));
  const auto help = runCli("montecarlo --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("writes nothing"), std::string::npos) << help.out;
}

// Fig. 8 places four poles and more beside the path; three stops 0.15 m apart leave too little
// room.
TEST(CliMonteCarlo, APathTooShortForItsLandmarksIsRefusedWithWhatToChange) {
  TempDir dir;
  const std::string out = (dir / "o").string();
  const auto r = runCli("montecarlo --study fig8 --trials 2 --stops 3 --out " + out);
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("lengthen the path"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliMonteCarlo, InterruptStopsCleanlyAndWritesNothing) {
  TempDir dir;
  const fs::path out = dir / "o";
  const fs::path err = dir / "err.txt";
  // A study far too long to finish, interrupted once it has started (its staging directory
  // exists: the SIGINT handler is installed before it is created).
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 2);
    ::execl(LIDARCAL_EXE, LIDARCAL_EXE, "montecarlo", "-q", "--study", "fig9", "--trials", "100000",
            "--threads", "2", "--out", out.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  auto staging = [&] {
    for (const auto& e : fs::directory_iterator(dir.path()))
      if (e.path().filename().string().rfind(".o.partial", 0) == 0) return true;
    return false;
  };
  bool started = false;
  for (int i = 0; i < 1200 && !started; ++i) {  // up to two minutes on a loaded machine
    started = staging();
    if (!started) ::usleep(100000);
  }
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(started) << "the study never started";
  ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal";
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_NE(test::readFile(err).find("nothing was written"), std::string::npos)
      << test::readFile(err);
  // Neither the output nor the staging directory is left.
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename(), "err.txt") << e.path();
}

}  // namespace
}  // namespace lidarcal
