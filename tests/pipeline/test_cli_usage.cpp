// SPDX-License-Identifier: BSD-3-Clause
// What a user meets at the command line before any work is done: help that fits an 80-column
// terminal, and parse errors that name what was not understood, in the order given, with the
// nearest command or option (pipeline/commands/cli_usage.hpp).

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "pipeline/commands/cli_usage.hpp"
#include "test_util.hpp"

namespace lidarcal::test {
namespace {

using pipeline::editDistance;
using pipeline::nearestName;
using pipeline::wrapText;

std::vector<std::string> linesOf(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

std::vector<std::string> wordsOf(const std::string& text) {
  std::vector<std::string> words;
  std::istringstream in(text);
  std::string w;
  while (in >> w) words.push_back(w);
  return words;
}

/// Every line of a command's stderr carries the program's prefix.
void expectPrefixed(const CliResult& r) {
  ASSERT_FALSE(r.err.empty());
  for (const std::string& line : linesOf(r.err))
    EXPECT_EQ(line.rfind("lidarcal: ", 0), 0u) << "unprefixed line: " << line << "\n" << r.err;
}

/// The commands `lidarcal --help` lists (names at column 2 under "Subcommands:").
std::vector<std::string> listedCommands() {
  const CliResult help = runCli("--help");
  EXPECT_EQ(help.exit_code, 0);
  std::vector<std::string> commands;
  bool inside = false;
  for (const std::string& line : linesOf(help.out)) {
    if (line.rfind("Subcommands:", 0) == 0) {
      inside = true;
    } else if (inside && line.empty()) {
      break;
    } else if (inside && line.size() > 2 && line.compare(0, 2, "  ") == 0 && line[2] != ' ') {
      commands.push_back(wordsOf(line).front());
    }
  }
  return commands;
}

TEST(EditDistance, CountsEditsAndSwapsOfNeighbours) {
  EXPECT_EQ(editDistance("", ""), 0u);
  EXPECT_EQ(editDistance("", "run"), 3u);
  EXPECT_EQ(editDistance("kitten", "sitting"), 3u);  // two substitutions and an insertion
  EXPECT_EQ(editDistance("calibrat", "calibrate"), 1u);
  EXPECT_EQ(editDistance("--radus", "--radius"), 1u);
  EXPECT_EQ(editDistance("exoprt", "export"), 1u);  // one swap, not two substitutions
  for (const auto& [a, b] : {std::pair<std::string, std::string>{"detect", "diagnose"},
                             {"fleet", "plot"},
                             {"montecarlo", "montecarlo-merge"}})
    EXPECT_EQ(editDistance(a, b), editDistance(b, a)) << a << " " << b;
}

TEST(NearestName, SuggestsASlipOrTheOnlyLongerNameAndNothingElse) {
  const std::vector<std::string> commands{"run",        "calibrate",        "correct", "export",
                                          "montecarlo", "montecarlo-merge", "plot",    "info"};
  EXPECT_EQ(nearestName("calibrat", commands), "calibrate");
  EXPECT_EQ(nearestName("corect", commands), "correct");
  EXPECT_EQ(nearestName("calib", commands), "calibrate");  // the only name it begins
  EXPECT_EQ(nearestName("montecarlo-m", commands), "montecarlo-merge");
  EXPECT_EQ(nearestName("mont", commands), "");  // begins two names
  EXPECT_EQ(nearestName("simulate", commands), "");
  EXPECT_EQ(nearestName("xyz", commands), "");
  EXPECT_EQ(nearestName("--radus", {"--radius", "--out", "-o"}), "--radius");
  EXPECT_EQ(nearestName("--foo", {"--radius", "--out", "-o"}), "");
}

TEST(WrapText, KeepsEveryWordAndTheDescriptionColumn) {
  const std::string description(
      "Inlier threshold of the circle and line fits, t(r) = A + B r^2 metres (r: range), as A,B; "
      "about three standard deviations of the sensor's range noise");
  std::string name = "  --inlier-threshold";
  name.resize(30, ' ');
  const std::string text = "Usage: lidarcal calibrate [OPTIONS] SEQ\n" + name + description +
                           "\nA footer line that runs on for a good deal longer than eighty "
                           "characters so that it must be wrapped too.\n";
  const std::string wrapped = wrapText(text, 80, 30);
  EXPECT_EQ(wordsOf(wrapped), wordsOf(text));
  const std::vector<std::string> lines = linesOf(wrapped);
  ASSERT_GE(lines.size(), 5u);
  EXPECT_EQ(lines[0], "Usage: lidarcal calibrate [OPTIONS] SEQ");
  EXPECT_EQ(lines[1].substr(0, 30), name);
  bool in_description = true;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    SCOPED_TRACE(lines[i]);
    EXPECT_LE(lines[i].size(), 80u);
    if (i > 1 && in_description && lines[i].rfind(std::string(30, ' '), 0) != 0)
      in_description = false;  // the footer starts
    if (i > 1 && in_description) {
      EXPECT_NE(lines[i][30], ' ');
    }
  }
  EXPECT_FALSE(in_description);
  // A word longer than the room left stays whole, on a line of its own.
  const std::string path(100, 'x');
  EXPECT_EQ(wordsOf(wrapText("see " + path + " now", 40, 30)),
            (std::vector<std::string>{"see", path, "now"}));
}

TEST(CliUsage, EveryCommandsHelpFitsEightyColumns) {
  const std::vector<std::string> commands = listedCommands();
  ASSERT_GE(commands.size(), 10u);
  std::vector<std::string> pages{""};  // the program's own help, then each command's
  pages.insert(pages.end(), commands.begin(), commands.end());
  for (const std::string& c : pages) {
    SCOPED_TRACE(c);
    const CliResult r = runCli(c + " --help");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (const std::string& line : linesOf(r.out))
      if (wordsOf(line).size() > 1) {
        EXPECT_LE(line.size(), 80u) << line;
      }
  }
}

TEST(CliUsage, AMisspelledCommandGetsTheNearestOne) {
  const CliResult r = runCli("calibrat /tmp/seq -o /tmp/model.json");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("'calibrat' is not a lidarcal command; did you mean `calibrate`?"),
            std::string::npos)
      << r.err;
  expectPrefixed(r);
  const CliResult none = runCli("");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("a command is required"), std::string::npos) << none.err;
  expectPrefixed(none);
}

TEST(CliUsage, UnexpectedArgumentsAreListedInTheOrderGivenWithTheNearestOption) {
  TempDir dir;
  const CliResult r = runCli("calibrate " + (dir / "seq").string() + " -o " +
                             (dir / "m.json").string() + " --radus 0.12 --foo");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("calibrate: not expected: --radus 0.12 --foo\n"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("--radus: unknown option; did you mean --radius?"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("--foo: unknown option\n"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("lidarcal calibrate --help"), std::string::npos) << r.err;
  expectPrefixed(r);
  EXPECT_FALSE(fs::exists(dir / "m.json"));
}

TEST(CliUsage, EveryErrorLineCarriesThePrefix) {
  TempDir dir;
  for (const std::string& args :
       {std::string("--vrsion"), "calibrate --method jont " + dir.path().string() + " -o m.json",
        "calibrate " + dir.path().string(), "info " + (dir / "missing").string(),
        "montecarlo --shard 4/3 -o " + (dir / "mc").string()}) {
    SCOPED_TRACE(args);
    const CliResult r = runCli(args);
    EXPECT_EQ(r.exit_code, 2);
    expectPrefixed(r);
  }
}

}  // namespace
}  // namespace lidarcal::test
