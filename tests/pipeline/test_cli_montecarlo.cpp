// `lidarcal montecarlo` end to end: the files it promises, the same bytes with 1 and 2 threads,
// refusals of bad options, and an interruption that leaves nothing behind.

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
const std::string kSmall = "montecarlo -q --quick --stops 8 --step 0.3 --scans-per-stop 3 --trials 4 --joint-trials 1 --seed 5";

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

TEST(CliMonteCarlo, RefusesBadOptions) {
  TempDir dir;
  const std::string out = (dir / "o").string();
  EXPECT_EQ(runCli("montecarlo --study fig12 --out " + out).exit_code, 2);
  EXPECT_EQ(runCli("montecarlo --level photons --out " + out).exit_code, 2);
  EXPECT_EQ(runCli("montecarlo --level scan --angle-noise bearing --out " + out).exit_code, 2);
  EXPECT_EQ(runCli("montecarlo --trials 0 --out " + out).exit_code, 2);
  EXPECT_FALSE(fs::exists(out));
  const auto help = runCli("montecarlo --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("writes nothing"), std::string::npos) << help.out;
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
    ::execl(LIDARCAL_EXE, LIDARCAL_EXE, "montecarlo", "-q", "--study", "fig9", "--trials", "100000", "--threads", "2",
            "--out", out.c_str(), static_cast<char*>(nullptr));
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
  EXPECT_NE(test::readFile(err).find("nothing was written"), std::string::npos) << test::readFile(err);
  // Neither the output nor the staging directory is left.
  for (const auto& e : fs::directory_iterator(dir.path())) EXPECT_EQ(e.path().filename(), "err.txt") << e.path();
}

}  // namespace
}  // namespace lidarcal
