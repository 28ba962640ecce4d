// SPDX-License-Identifier: BSD-3-Clause
// What a new user meets in the first hour: progress counts, the report's plots over the fitted
// range, `plot`'s titles, legends and refusal to overwrite, `-o`, `info --json`, observations.csv
// ids as labels, `correct --force`, the words of --help and `run`, and the messages for a
// directory or a 3D cloud where a scan is expected. Import's format detection:
// tests/io/test_detect_format.cpp.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/gnuplot.hpp"
#include "io/model_io.hpp"
#include "io/sequence.hpp"
#include "pipeline/commands/cli_options.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/words.hpp"
#include "pipeline/stages/stages.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

namespace fs = std::filesystem;
using namespace std::string_literals;
using test::readFile;
using test::runCli;
using test::runCliPrefixed;
using test::TempDir;
using test::writeFile;

nlohmann::json json(const fs::path& p) { return nlohmann::json::parse(readFile(p)); }

std::string scene(const char* name) { return (test::sourceDir() / "data/scenes" / name).string(); }

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// Rows of a whitespace-separated data file (blank lines skipped).
std::vector<std::vector<double>> rows(const fs::path& file) {
  std::vector<std::vector<double>> out;
  std::istringstream in(readFile(file));
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::vector<double> row;
    std::string w;
    while (words >> w) row.push_back(std::strtod(w.c_str(), nullptr));
    if (!row.empty()) out.push_back(row);
  }
  return out;
}

/// Two small simulated sequences of the paper's field (10 stops, 3 scans each), shared by the
/// suite.
class FirstHour : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    for (const char* name : {"a", "b"}) {
      const auto r = runCli("simulate -q --scene " + scene("paper_field.json") + " -o " +
                            (dir_->path() / name).string() + " --seed " +
                            (name[0] == 'a' ? "31" : "32") + " --scans-per-stop 3");
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static fs::path a() { return dir_->path() / "a"; }
  static fs::path b() { return dir_->path() / "b"; }
  static TempDir* dir_;
};
TempDir* FirstHour::dir_ = nullptr;

// ---- progress

TEST(ProgressText, CountNeverRunsPastTheTotalAndTimeLeftNeverGoesNegative) {
  using pipeline::progressText;
  // 1820 scans done of 910 (the detector's second pass reported against the first total).
  const std::string past = progressText("detect", 1820, 910, 10.0, false);
  EXPECT_TRUE(contains(past, "910/910")) << past;
  EXPECT_FALSE(contains(past, "1820")) << past;
  EXPECT_TRUE(contains(past, "0 s left")) << past;
  EXPECT_EQ(past.find('-'), std::string::npos) << past;
  // Half way after 10 s: 10 s left; the bar is half full.
  const std::string half = progressText("detect", 50, 100, 10.0, false);
  EXPECT_TRUE(contains(half, "50/100")) << half;
  EXPECT_TRUE(contains(half, "10 s left")) << half;
  EXPECT_TRUE(contains(half, "[###############...............]")) << half;
  EXPECT_TRUE(contains(progressText("detect", 10, 1000, 5.0, false), "8 min 15 s left"));
  // Nothing done yet: no rate, no division by zero.
  EXPECT_TRUE(contains(progressText("correct", 0, 100, 0.0, false), "starting"));
  // Final line: the total and the time taken.
  EXPECT_TRUE(contains(progressText("correct", 100, 100, 3.4, true), "100/100 in 3.4 s"));
  // Unknown total: the name and the time spent, no bar.
  const std::string unknown =
      progressText("diagnose (repeated scans of one pose)", 0, 0, 14.0, false);
  EXPECT_EQ(unknown, "diagnose (repeated scans of one pose) ... 14.0 s");
  EXPECT_EQ(progressText("ml iterations", 12, 0, 2.0, true), "ml iterations 12 done in 2.0 s");
}

TEST_F(FirstHour, EveryStageReportsItsOwnProgressUpToItsTotal) {
  const io::Sequence seq = io::openSequence(a() / "scans");
  pipeline::CalibrationOptions options;
  struct Seen {
    std::size_t calls = 0, last = 0, total = 0;
    bool monotone = true, within = true;
  };
  std::map<std::string, Seen> seen;
  std::vector<std::string> order;
  const auto cal = pipeline::calibrateSequence(
      seq, pipeline::detectionConfig(options), pipeline::calibrationConfig(options),
      [&](const std::string& stage, std::size_t done, std::size_t total) {
        if (!seen.count(stage)) order.push_back(stage);
        Seen& s = seen[stage];
        if (s.calls && done < s.last) s.monotone = false;
        if (done > total) s.within = false;
        ++s.calls;
        s.last = done;
        s.total = total;
      });
  ASSERT_STREQ(cal.model.status.name(), "ok") << cal.model.status.message;
  EXPECT_EQ(order, (std::vector<std::string>{"detect", "joint refinement"}));
  for (const auto& [stage, s] : seen) {
    SCOPED_TRACE(stage);
    EXPECT_TRUE(s.monotone);
    EXPECT_TRUE(s.within);
    EXPECT_EQ(s.last, s.total);  // every stage ends at its total
  }
  // The radius is in sequence.json: one pass over the scans.
  EXPECT_EQ(seen["detect"].total, seq.scans.size());
  // The settling pass, one solve per order (max order 4), the covariance.
  EXPECT_EQ(seen["joint refinement"].total, 1u + 4u + 1u);
  // 0, 1, ..., total
  EXPECT_EQ(seen["joint refinement"].calls, seen["joint refinement"].total + 1);
}

TEST_F(FirstHour, DetectionWithAnEstimatedRadiusCountsBothPassesAgainstOneTotal) {
  // Without the radius the detector reads every scan twice: the total says so from the start.
  TempDir dir;
  fs::create_directories(dir / "s");
  for (const auto& e : fs::directory_iterator(a() / "scans"))
    if (e.path().extension() == ".pcd") fs::copy_file(e.path(), dir / "s" / e.path().filename());
  const io::Sequence seq = io::openSequence(dir / "s");
  ASSERT_FALSE(seq.meta.landmark_radius_m.has_value());
  std::size_t first_total = 0, last = 0, largest_total = 0;
  bool within = true;
  detectors::detectSequence(seq, detectors::SequenceDetectionConfig{},
                            [&](std::size_t done, std::size_t total) {
                              if (!first_total) first_total = total;
                              largest_total = std::max(largest_total, total);
                              within = within && done <= total;
                              last = done;
                            });
  EXPECT_TRUE(within);
  EXPECT_EQ(first_total, 2 * seq.scans.size());
  EXPECT_EQ(largest_total, first_total);
  EXPECT_EQ(last, first_total);
}

// ---- report

/// What the report's distance plot holds: its readings, those corrected, and the model's fitted
/// range, metres.
struct DistancePlot {
  std::size_t readings = 0, corrected = 0;
  double lo_m = 0.0, hi_m = 0.0;
};

/// distance.dat in the report `rep`: the residuals after correction are the small ones, and the
/// fitted range of the model file covers every reading the fit used.
void expectReadingsInsideTheFittedRange(const fs::path& rep, const fs::path& model_file,
                                        DistancePlot& plot) {
  // The fitted range: the estimated distances of the readings (distance.dat column 1).
  const auto dist = rows(rep / "distance.dat");
  ASSERT_GT(dist.size(), 100u);
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  std::size_t corrected = 0;
  double raw_sq = 0.0, cor_sq = 0.0;
  for (const auto& row : dist) {
    ASSERT_EQ(row.size(), 3u);  // d, raw reading, corrected reading
    lo = std::min(lo, row[0]);
    hi = std::max(hi, row[0]);
    if (std::isfinite(row[2])) {
      ++corrected;
      raw_sq += (row[1] - row[0]) * (row[1] - row[0]);
      cor_sq += (row[2] - row[0]) * (row[2] - row[0]);
    }
  }
  EXPECT_GT(corrected, dist.size() * 9 / 10);
  EXPECT_LT(cor_sq, raw_sq / 10.0);  // the residuals after correction are the small ones
  // The paper field's sensor reads to 6 m; the poles are within about 4 m of the stops.
  ASSERT_LT(hi, 5.0);
  // The model's fitted range covers every reading the fit used.
  const auto model = io::readModel(model_file);
  ASSERT_TRUE(model.fitted_range_m.has_value());
  EXPECT_LE(model.fitted_range_m->first, lo);
  EXPECT_GE(model.fitted_range_m->second, hi);
  for (const auto& row : dist) {  // distance.dat holds six significant digits
    EXPECT_GE(row[1], model.model.bias(model.fitted_range_m->first) - 1e-5);
    EXPECT_LE(row[1], model.model.bias(model.fitted_range_m->second) + 1e-5);
  }
  plot = {dist.size(), corrected, model.fitted_range_m->first, model.fitted_range_m->second};
}

/// plots.gp and its data in the report `rep`: drawn over the fitted range with a margin, the
/// residuals after correction and the histogram plotted, legends outside, stops numbered.
void expectThePlotsOverTheFittedRange(const fs::path& rep, const DistancePlot& plot) {
  const double lo = plot.lo_m, hi = plot.hi_m;
  // The script's x range is the fitted one with a margin, not 0..range_max.
  const std::string gp = readFile(rep / "plots.gp");
  const auto at = gp.find("set xrange [");
  ASSERT_NE(at, std::string::npos) << gp;
  double x0 = 0, x1 = 0;
  ASSERT_EQ(std::sscanf(gp.c_str() + at, "set xrange [%lf:%lf]", &x0, &x1), 2) << gp.substr(at, 40);
  const double margin = std::max(0.1, 0.1 * (hi - lo));
  EXPECT_NEAR(x0, std::max(0.0, lo - margin), 1e-4);
  EXPECT_NEAR(x1, hi + margin, 1e-4);
  EXPECT_LT(x1, 6.0);
  // The fitted curve is drawn over that range only.
  const auto curve = rows(rep / "curve.dat");
  ASSERT_FALSE(curve.empty());
  EXPECT_NEAR(curve.front()[0], x0, 1e-4);
  EXPECT_NEAR(curve.back()[0], x1, 1e-4);
  // Residuals after correction and the before/after histogram are plotted; legends outside.
  EXPECT_TRUE(contains(gp, "set output \"residuals.svg\"")) << gp;
  EXPECT_TRUE(contains(gp, "using 1:(1000*($3-$1))")) << gp;
  EXPECT_TRUE(contains(gp, "set output \"histogram.svg\"")) << gp;
  EXPECT_TRUE(contains(gp, "set key outside")) << gp;
  EXPECT_FALSE(contains(gp, "set key top left")) << gp;
  const auto hist = rows(rep / "histogram.dat");
  double n_raw = 0, n_cor = 0;
  for (const auto& row : hist) {
    n_raw += row[1];
    n_cor += row[2];
  }
  EXPECT_GT(n_raw, 0.9 * static_cast<double>(plot.readings));
  EXPECT_GT(n_cor, 0.9 * static_cast<double>(plot.corrected));
  // Stops are numbered on the map (x, y, number).
  const auto stops = rows(rep / "stops.dat");
  ASSERT_EQ(stops.size(), 10u);
  for (std::size_t k = 0; k < stops.size(); ++k) EXPECT_EQ(stops[k][2], static_cast<double>(k));
  EXPECT_TRUE(contains(gp, "with labels")) << gp;
  EXPECT_TRUE(contains(gp, "label_every = 1\n")) << gp;  // 10 stops: every one numbered
}

/// report.md in `rep`: rows beyond the fitted range marked extrapolated, those inside fitted;
/// every picture it shows drawn.
void expectTheErrorTableAndItsPictures(const fs::path& rep) {
  // The error table: rows beyond the fitted range are marked extrapolated, those inside fitted.
  const std::string md = readFile(rep / "report.md");
  EXPECT_TRUE(contains(md, "| 5.00 m * |")) << md;
  EXPECT_TRUE(contains(md, "extrapolated |")) << md;
  EXPECT_TRUE(contains(md, "| 2.00 m | ")) << md;
  EXPECT_TRUE(contains(md, "fitted |")) << md;
  EXPECT_FALSE(contains(md, "seed 00")) << md;
  EXPECT_TRUE(contains(md, "Alhashimi et al. 2016")) << md;
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    // Every picture the report shows was drawn, as an SVG document.
    std::size_t images = 0;
    for (std::size_t pos = md.find("]("); pos != std::string::npos; pos = md.find("](", pos + 2)) {
      const std::string name = md.substr(pos + 2, md.find(')', pos) - pos - 2);
      if (name.size() < 4 || name.substr(name.size() - 4) != ".svg") continue;
      ++images;
      ASSERT_TRUE(fs::exists(rep / name)) << name;
      EXPECT_TRUE(contains(readFile(rep / name), "<svg")) << name;
    }
    EXPECT_GE(images, 5u) << md;
  }
}

TEST_F(FirstHour, ReportPlotsTheFittedRangeWithResidualsAfterCorrectionAndMarksExtrapolation) {
  TempDir out;
  const auto r = runCli("calibrate -q " + (a() / "scans").string() + " -o " +
                        (out / "m.json").string() + " --report " + (out / "report").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path rep = out / "report";
  DistancePlot plot;
  ASSERT_NO_FATAL_FAILURE(expectReadingsInsideTheFittedRange(rep, out / "m.json", plot));
  ASSERT_NO_FATAL_FAILURE(expectThePlotsOverTheFittedRange(rep, plot));
  // No truth was given: no true landmarks.
  EXPECT_FALSE(fs::exists(rep / "truth.dat"));
  expectTheErrorTableAndItsPictures(rep);
}

TEST_F(FirstHour, RunDrawsTheTrueLandmarksAndExplainsTheMseRatio) {
  TempDir out;
  const auto r = runCli("run " + (a() / "scans").string() + " -o " + (out / "o").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The true landmarks (5 poles) are drawn on the map: 5 circles of 73 points each.
  const auto truth = rows(out / "o/report/truth.dat");
  EXPECT_EQ(truth.size(), 5u * 73u);
  EXPECT_TRUE(contains(readFile(out / "o/report/plots.gp"), "\"truth.dat\""))
      << readFile(out / "o/report/plots.gp");
  // The printed summary says what the MSE ratio means and gives the RMS in mm before and after.
  EXPECT_TRUE(contains(r.out, "raw MSE / corrected MSE: higher is better")) << r.out;
  EXPECT_TRUE(contains(r.out, "raw readings, RMS:")) << r.out;
  EXPECT_TRUE(contains(r.out, "the written scans, MSE ratio:")) << r.out;
  EXPECT_TRUE(contains(r.out, "10 stops, 5 landmarks")) << r.out;
  EXPECT_FALSE(contains(r.out, "seed 00")) << r.out;
  // Running again into the same OUT is refused with the way out named.
  const auto again = runCli("run -q " + (a() / "scans").string() + " -o " + (out / "o").string());
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_TRUE(contains(again.err, "already exists")) << again.err;
  EXPECT_TRUE(contains(again.err, "--overwrite")) << again.err;
}

TEST_F(FirstHour, RunPrintsTheCorrectedRmsAndTakesTheOutsideRule) {
  TempDir out;
  for (const char* outside : {"linear", "drop"}) {
    SCOPED_TRACE(outside);
    const fs::path o = out / outside;
    const auto r = runCli("run -q " + (a() / "scans").string() + " --outside " + outside + " -o " +
                          o.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json summary = json(o / "summary.json");
    EXPECT_EQ(summary.at("outside"), outside);
    // The corrected RMS on the poles, as evaluate's MSE gives it, next to the raw one.
    const std::string row = "corrected readings (the written scans), RMS:";
    const auto at = r.out.find(row);
    ASSERT_NE(at, std::string::npos) << r.out;
    const double printed_mm = std::strtod(r.out.c_str() + at + row.size(), nullptr);
    const auto& landmarks = summary.at("evaluation").at("landmarks");
    EXPECT_NEAR(printed_mm, 1000.0 * std::sqrt(landmarks.at("mse_corrected_m2").get<double>()),
                0.05);
    EXPECT_LT(printed_mm, 1000.0 * std::sqrt(landmarks.at("mse_raw_m2").get<double>()) / 5.0);
  }
}

// ---- plot

/// A fake gnuplot first on PATH (in `dir`, which must outlive it): keeps the script it was given
/// and draws a stand-in PNG.
struct GnuplotStub {
  fs::path dir;
  explicit GnuplotStub(fs::path where) : dir(std::move(where)) {
    fs::create_directories(dir / "bin");
    fs::create_directories(dir / "seen");
    writeFile(dir / "bin/gnuplot", "#!/bin/sh\ncp \"$1\" '" + (dir / "seen/script.gp").string() +
                                       "'\nfor f in *.dat; do cp \"$f\" '" +
                                       (dir / "seen").string() +
                                       "/'; done\nprintf '\\211PNG stub' > plot.png\n");
    fs::permissions(dir / "bin/gnuplot", fs::perms::owner_all);
  }
  std::string prefix() const { return "export PATH='" + (dir / "bin").string() + "':\"$PATH\""; }
  std::string script() const { return readFile(dir / "seen/script.gp"); }
};

TEST_F(FirstHour, PlotEscapesTheTitleAndListsOnlyTheSeriesItDraws) {
  TempDir out;
  const GnuplotStub stub(out / "stub");
  // An unlabelled scan: no landmark points, no circles.
  const auto r = runCliPrefixed(stub.prefix(), "plot " + (a() / "scans/scan_000000.pcd").string() +
                                                   " -o " + (out / "scan.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string gp = stub.script();
  EXPECT_TRUE(
      contains(gp, "set title \"scan\\\\_000000.pcd (sensor frame; 0 points on landmarks)\""))
      << gp;
  EXPECT_FALSE(contains(gp, "landmark points")) << gp;
  EXPECT_FALSE(contains(gp, "fitted circles")) << gp;
  EXPECT_TRUE(contains(gp, "title \"points\"")) << gp;
  EXPECT_TRUE(contains(gp, "title \"sensor\"")) << gp;
  // Every markup character of gnuplot's enhanced text is escaped.
  const auto t =
      runCliPrefixed(stub.prefix(), "plot " + (a() / "scans/scan_000000.pcd").string() + " -o " +
                                        (out / "t.png").string() + " --title 'a_b^c{d}e@f&g~h\"i'");
  ASSERT_EQ(t.exit_code, 0) << t.err;
  EXPECT_TRUE(contains(
      stub.script(), "set title \"a\\\\_b\\\\^c\\\\{d\\\\}e\\\\@f\\\\&g\\\\~h\\\"i (sensor frame"))
      << stub.script();
  // A labelled scan with its circles lists both.
  const auto d = runCli("detect -q " + (a() / "scans").string() + " -o " + (out / "d").string());
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const auto l = runCliPrefixed(
      stub.prefix(), "plot " + (out / "d/scan_000000.pcd").string() + " --landmarks " +
                         (out / "d/landmarks.csv").string() + " -o " + (out / "l.png").string());
  ASSERT_EQ(l.exit_code, 0) << l.err;
  EXPECT_TRUE(contains(stub.script(), "landmark points (label > 0)")) << stub.script();
  EXPECT_TRUE(contains(stub.script(), "fitted circles")) << stub.script();
  EXPECT_TRUE(contains(stub.script(), "background (label 0)")) << stub.script();
}

TEST_F(FirstHour, PlotRefusesToOverwriteUnlessAsked) {
  TempDir out;
  const GnuplotStub stub(out / "stub");
  writeFile(out / "scan.png", "mine");
  const std::string args =
      "plot " + (a() / "scans/scan_000000.pcd").string() + " -o " + (out / "scan.png").string();
  const auto r = runCliPrefixed(stub.prefix(), args);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.err, "already exists")) << r.err;
  EXPECT_TRUE(contains(r.err, "--overwrite")) << r.err;
  EXPECT_EQ(readFile(out / "scan.png"), "mine");
  const auto o = runCliPrefixed(stub.prefix(), args + " --overwrite");
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_EQ(readFile(out / "scan.png"), "\211PNG stub");
}

TEST_F(FirstHour, ADirectoryOrA3dCloudWhereAScanIsExpectedIsNamed) {
  TempDir out;
  const auto r = runCli("plot " + (a() / "scans").string() + " -o " + (out / "x.png").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(
      r.err, "is a directory; give a .pcd file (e.g. " + (a() / "scans/scan_000000.pcd").string()))
      << r.err;
  EXPECT_FALSE(contains(r.err, "DATA line")) << r.err;
  // An organised 3D cloud, as PCL writes them (2 x 2 points, VIEWPOINT with a roll).
  writeFile(out / "cloud.pcd",
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT "
            "2\nVIEWPOINT 0 0 0 0 1 0 0\n"
            "POINTS 4\nDATA ascii\n0 0 1\n0.1 0 1\n0 0.1 1\n0.1 0.1 1\n");
  const auto c = runCli("plot " + (out / "cloud.pcd").string() + " -o " + (out / "y.png").string());
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_TRUE(contains(c.err, "this is a 3D organised cloud (2x2 points)")) << c.err;
  EXPECT_TRUE(contains(c.err, "detectCylinder")) << c.err;
  EXPECT_FALSE(contains(c.err, "roll/pitch")) << c.err;
  const fs::path mug = test::sharedData() / "pcl/table_scene_mug_stereo_textured.pcd";
  if (!fs::exists(mug)) GTEST_SKIP() << "shared data absent: " << mug;
  fs::create_directories(out / "seq");
  fs::copy_file(mug, out / "seq/scan_000000.pcd");
  for (const std::string& cmd : {"plot " + mug.string() + " -o " + (out / "z.png").string(),
                                 "info " + (out / "seq").string()}) {
    const auto m = runCli(cmd);
    EXPECT_EQ(m.exit_code, 2) << cmd;
    EXPECT_TRUE(contains(m.err, "this is a 3D organised cloud (640x480 points)")) << m.err;
  }
}

// ---- conventions

TEST(Conventions, EveryCommandWithOutAcceptsDashO) {
  const auto help = runCli("--help");
  ASSERT_EQ(help.exit_code, 0);
  std::size_t with_out = 0;
  for (const char* cmd :
       {"simulate", "info", "run", "calibrate", "correct", "evaluate", "import", "detect", "plot",
        "noise-consistency", "landmarks-to-observations", "montecarlo", "diagnose"}) {
    SCOPED_TRACE(cmd);
    const auto r = runCli(std::string(cmd) + " --help");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    if (contains(r.out, "--out")) {
      ++with_out;
      EXPECT_TRUE(contains(r.out, "-o,--out")) << r.out;
    }
    // The papers are named by author and year.
    EXPECT_FALSE(contains(r.out, "seed 00")) << r.out;
    EXPECT_FALSE(contains(r.out, "seeds'")) << r.out;
  }
  EXPECT_EQ(with_out, 12u);
  EXPECT_FALSE(contains(help.out, "seed 00")) << help.out;
  EXPECT_TRUE(contains(help.out, "Alhashimi et al. 2021")) << help.out;
  EXPECT_TRUE(contains(help.out, "Alhashimi et al. 2016")) << help.out;
  EXPECT_TRUE(contains(help.out, "Sharma 2020")) << help.out;
}

TEST_F(FirstHour, InfoJsonCarriesTheSummaryForScripts) {
  const auto r = runCli("info -q --json " + (a() / "scans").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["scans"], 30);
  EXPECT_EQ(j["stops"], 10);
  EXPECT_EQ(j["scans_per_stop"]["min"], 3);
  EXPECT_EQ(j["beams_per_scan"]["max"], 360);
  EXPECT_EQ(j["sequence_json"]["range_max_m"], 6.0);
  EXPECT_NEAR(j["commanded_path_m"].get<double>(), 9 * 0.30, 1e-3);
  EXPECT_LE(j["returns"].get<std::size_t>(), j["points"].get<std::size_t>());
  // The Markdown form says "3 scans each" and, for one scan per stop, "1 scan each".
  EXPECT_TRUE(contains(runCli("info -q " + (a() / "scans").string()).out, "(3 scans each)"));
}

TEST_F(FirstHour, CorrectRefusesOtherRangeLimitsUnlessForced) {
  TempDir out;
  ASSERT_EQ(runCli("calibrate -q " + (a() / "scans").string() + " -o " + (out / "m.json").string())
                .exit_code,
            0);
  auto j = json(out / "m.json");
  j["sensor"]["range_max_m"] = 8.0;  // same sensor name, other limit
  writeFile(out / "limits.json", j.dump());
  const std::string args =
      "correct " + (b() / "scans").string() + " --model " + (out / "limits.json").string();
  const auto refused = runCli(args + " -o " + (out / "c1").string());
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_TRUE(contains(refused.err, "range limits")) << refused.err;
  EXPECT_TRUE(contains(refused.err, "--force")) << refused.err;
  EXPECT_FALSE(fs::exists(out / "c1"));
  const auto forced = runCli(args + " -o " + (out / "c2").string() + " --force");
  ASSERT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_TRUE(contains(forced.err, "warning")) << forced.err;
  EXPECT_TRUE(contains(forced.err, "--force")) << forced.err;
  EXPECT_EQ(io::openSequence(out / "c2").scans.size(), 30u);
  // A model of another sensor (another name) stays refused, --force or not.
  j = json(out / "m.json");
  j["sensor"]["name"] = "another lidar";
  j["sensor"]["range_max_m"] = 8.0;
  writeFile(out / "other.json", j.dump());
  const auto other =
      runCli("correct " + (b() / "scans").string() + " --model " + (out / "other.json").string() +
             " -o " + (out / "c3").string() + " --force");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_TRUE(contains(other.err, "another sensor")) << other.err;
}

TEST(ObservationIds, AnyIntegerSensorIdsAreLabelsKeptInTheResult) {
  TempDir dir;
  ASSERT_EQ(runCli("simulate -q --scene " + scene("noise_exp12.json") + " -o " +
                   (dir / "sim").string() + " --seed 3")
                .exit_code,
            0);
  // The same observations with sensors 0, 1 renamed 40, -7 and landmarks shifted by 1000.
  std::istringstream in(readFile(dir / "sim/observations.csv"));
  std::ostringstream relabelled;
  std::string line;
  std::getline(in, line);
  relabelled << line << '\n';
  while (std::getline(in, line)) {
    int stop = 0, sensor = 0, landmark = 0;
    char rest[128] = {};
    ASSERT_EQ(std::sscanf(line.c_str(), "%d,%d,%d,%127s", &stop, &sensor, &landmark, rest), 4)
        << line;
    relabelled << stop << ',' << (sensor == 0 ? 40 : -7) << ','
               << (landmark < 0 ? -1 : landmark + 1000) << ',' << rest << '\n';
  }
  writeFile(dir / "relabelled.csv", relabelled.str());
  const std::string odo = " --odometry " + (dir / "sim/odometry.csv").string() + " --method ml";
  ASSERT_EQ(
      runCli("noise-consistency -q --observations " + (dir / "sim/observations.csv").string() +
             odo + " -o " + (dir / "plain.json").string())
          .exit_code,
      0);
  const auto r = runCli("noise-consistency -q --observations " + (dir / "relabelled.csv").string() +
                        odo + " -o " + (dir / "labelled.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto plain = json(dir / "plain.json");
  const auto labelled = json(dir / "labelled.json");
  // Sensors in ascending order of their labels: -7 (was 1), then 40 (was 0); the same estimates.
  ASSERT_EQ(labelled["sensors"].size(), 2u);
  EXPECT_EQ(labelled["sensors"][0]["sensor"], -7);
  EXPECT_EQ(labelled["sensors"][1]["sensor"], 40);
  for (const char* field : {"range_var_m2", "bearing_var_rad2", "range_mean_m"}) {
    SCOPED_TRACE(field);
    const double a0 = plain["sensors"][1][field].get<double>(),
                 a1 = plain["sensors"][0][field].get<double>();
    EXPECT_NEAR(labelled["sensors"][0][field].get<double>(), a0,
                1e-6 * std::max(1.0, std::abs(a0)));
    EXPECT_NEAR(labelled["sensors"][1][field].get<double>(), a1,
                1e-6 * std::max(1.0, std::abs(a1)));
  }
  EXPECT_EQ(labelled["data"]["landmarks"], plain["data"]["landmarks"]);
}

TEST(Words, PluralsAndGnuplotStrings) {
  EXPECT_EQ(pipeline::plural(1, "stop"), "1 stop");
  EXPECT_EQ(pipeline::plural(0, "stop"), "0 stops");
  EXPECT_EQ(pipeline::plural(2, "stop"), "2 stops");
  EXPECT_EQ(io::gnuplotString("scan_1.pcd"), "\"scan_1.pcd\"");
  EXPECT_EQ(io::gnuplotString("scan_1.pcd", true), "\"scan\\\\_1.pcd\"");
}

}  // namespace
}  // namespace lidarcal
