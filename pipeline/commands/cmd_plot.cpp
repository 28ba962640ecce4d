// SPDX-License-Identifier: BSD-3-Clause
// lidarcal plot SCAN.pcd --out scan.png [--landmarks landmarks.csv]: a scan as a picture, in the
// sensor frame, points coloured by their `label` (landmark id; grey for background), with the
// circles detect fitted to it.

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <sstream>
#include <vector>

#include <CLI/CLI.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/gnuplot.hpp"
#include "io/landmarks_csv.hpp"
#include "io/output_files.hpp"
#include "io/pcd_scan.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/reports/words.hpp"

namespace lidarcal::pipeline {
namespace {

struct PlotOptions {
  std::string scan, out, landmarks, title;
  bool overwrite = false;
};

void runPlot(const PlotOptions& o) {
  namespace fs = std::filesystem;
  io::checkOutputFile(o.out, o.overwrite);
  const io::Scan scan = io::readScan(o.scan);
  std::ostringstream background, labelled, circles;
  std::size_t n_labelled = 0, n_background = 0, n_circles = 0;
  for (std::size_t i = 0; i < scan.cloud->size(); ++i) {
    const auto& p = (*scan.cloud)[i];
    if (!std::isfinite(p.x)) continue;
    const std::uint32_t label = scan.labels.empty() ? 0 : scan.labels[i];
    if (label == 0) {
      background << p.x << ' ' << p.y << '\n';
      ++n_background;
    } else {
      labelled << p.x << ' ' << p.y << ' ' << label << '\n';
      ++n_labelled;
    }
  }
  if (!o.landmarks.empty()) {
    const std::string name = fs::path(o.scan).filename().string();
    for (const auto& row : io::readLandmarksCsv(o.landmarks)) {
      if (row.file != name) continue;
      for (int k = 0; k <= 72; ++k) {
        const double a = 2.0 * 3.14159265358979323846 * k / 72.0;
        circles << row.centre_x_m + row.radius_m * std::cos(a) << ' '
                << row.centre_y_m + row.radius_m * std::sin(a) << ' ' << row.landmark << '\n';
      }
      circles << '\n';
      ++n_circles;
    }
  }
  // Plot in a scratch directory beside the output, then move the PNG into place.
  const fs::path out = o.out;
  const fs::path work = (out.has_parent_path() ? out.parent_path() : fs::path(".")) /
                        ("." + out.filename().string() + ".plot");
  const io::ScratchDirectory scratch(work);
  io::writeTextAtomically(work / "background.dat", background.str() + "nan nan\n");
  io::writeTextAtomically(work / "labelled.dat", labelled.str() + "nan nan 0\n");
  io::writeTextAtomically(work / "circles.dat", circles.str() + "nan nan 0\n");
  const std::string title = o.title.empty() ? fs::path(o.scan).filename().string() : o.title;
  // One series per kind of thing the scan has: a legend entry only for what is drawn.
  std::vector<std::string> series;
  if (n_background)
    series.push_back(
        "\"background.dat\" using 1:2 with points pt 7 ps 0.35 lc rgb \"#aaaaaa\" title \"" +
        std::string(scan.labels.empty() ? "points" : "background (label 0)") + "\"");
  if (n_labelled)
    series.push_back(
        "\"labelled.dat\" using 1:2:(int($3)%5) with points pt 7 ps 0.9 lc palette title "
        "\"landmark points (label > 0)\"");
  if (n_circles)
    series.push_back(
        "\"circles.dat\" using 1:2 with lines lw 1.5 lc rgb \"black\" title \"fitted circles\"");
  series.push_back("\"+\" using (0):(0) with points pt 9 ps 2 lc rgb \"#0044aa\" title \"sensor\"");
  std::ostringstream gp;
  gp << "set terminal pngcairo size 900,900 font \"DejaVu Sans,11\"\n"
     << "set output \"plot.png\"\nset size ratio -1\nset grid\nset key outside below horizontal\n"
     << "set title "
     << io::gnuplotString(
            title + " (sensor frame; " + plural(n_labelled, "point") + " on landmarks)", true)
     << "\n"
     << "set xlabel \"x [m] (forward)\"\nset ylabel \"y [m] (left)\"\nset palette defined (0 "
        "'#1b9e77', 1 '#d95f02', 2 '#7570b3', 3 '#e7298a', 4 '#66a61e')\n"
     << "unset colorbox\nplot ";
  for (std::size_t i = 0; i < series.size(); ++i) gp << (i ? ", \\\n     " : "") << series[i];
  gp << "\n";
  io::writeTextAtomically(work / "plot.gp", gp.str());
  std::string why;
  if (!io::runGnuplot(work, "plot.gp", &why))
    throw InputError(o.out, "", why, "install gnuplot-nox (scripts/install-deps.sh)");
  scratch.moveOut("plot.png", out);
}

}  // namespace

void addPlotCommand(CLI::App& app) {
  auto o = std::make_shared<PlotOptions>();
  CLI::App* sub = app.add_subcommand(
      "plot", "Draw one scan as a PNG, points coloured by label (output of detect)");
  sub->add_option("SCAN", o->scan, "A .pcd scan (labelled by lidarcal detect, or not)")->required();
  sub->add_option("-o,--out", o->out, "PNG to write")->required();
  sub->add_flag("--overwrite", o->overwrite, "Replace --out if it exists");
  sub->add_option("--landmarks", o->landmarks,
                  "landmarks.csv from lidarcal detect: also draw the fitted circles");
  sub->add_option("--title", o->title, "Title of the picture (default: the file name)");
  sub->callback([o] { runPlot(*o); });
}

}  // namespace lidarcal::pipeline
