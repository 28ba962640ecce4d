// SPDX-License-Identifier: BSD-3-Clause
// The RPLIDAR A2 recording against the laser-meter references (docs/FINDINGS.md):
// ../shared/data/rplidar_a2_room/distance_comparison.md gives six wall-to-wall distances
// measured with two laser distance meters and a folding rule, layout_measurements_FK35.png
// where they were taken. This program fits straight lines to the mean scan (each beam averaged
// over all scans) where the walls of the plan are, reproduces the six measurements in the scan
// and estimates the lidar's range offset from them.
//   build/pipeline/lidarcal import --from rosbag1 ../shared/data/rplidar_a2_room/rplidar_1.bag
//   --out /tmp/rplidar
//   build/bench/rplidar_reference /tmp/rplidar [--plot DIR]   (DIR/rplidar_walls.png with gnuplot)
//
// The walls (beam index = degrees from angle_min = -180 degrees; see the plot made by
// `lidarcal diagnose` and docs/FINDINGS.md): the plan's top wall, where the six lines start from,
// is the scan's south-west side (beams 28-68); its left wall the south-east side (108-135); the
// right wall, next to the top wall, beams 339-350; the cabinet face, further down the right
// side, beams 290-325; the bottom side, beams 205-260.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "io/pcd_scan.hpp"
#include "io/sequence.hpp"

namespace {

struct Line {
  double nx = 0, ny = 0, d = 0, rms = 0;  // nx x + ny y = d, |n| = 1, d >= 0
  int n = 0;
};

using Points = std::map<int, std::pair<double, double>>;

Line fit(const Points& p, int lo, int hi, const Line* parallel_to = nullptr) {
  double mx = 0, my = 0;
  int n = 0;
  for (int b = lo; b <= hi; ++b)
    if (p.count(b)) {
      mx += p.at(b).first;
      my += p.at(b).second;
      ++n;
    }
  mx /= n;
  my /= n;
  Line l;
  l.n = n;
  if (parallel_to) {
    l.nx = -parallel_to->nx;  // the opposite wall: normal pointing the other way from the sensor
    l.ny = -parallel_to->ny;
  } else {
    double sxx = 0, syy = 0, sxy = 0;
    for (int b = lo; b <= hi; ++b)
      if (p.count(b)) {
        const double dx = p.at(b).first - mx, dy = p.at(b).second - my;
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
      }
    const double th = 0.5 * std::atan2(2 * sxy, sxx - syy);
    l.nx = -std::sin(th);
    l.ny = std::cos(th);
  }
  l.d = l.nx * mx + l.ny * my;
  if (l.d < 0) {
    l.nx = -l.nx;
    l.ny = -l.ny;
    l.d = -l.d;
  }
  double ss = 0;
  for (int b = lo; b <= hi; ++b)
    if (p.count(b)) ss += std::pow(l.nx * p.at(b).first + l.ny * p.at(b).second - l.d, 2);
  l.rms = std::sqrt(ss / n);
  return l;
}

std::pair<double, double> intersect(const Line& a, const Line& b) {
  const double det = a.nx * b.ny - a.ny * b.nx;
  return {(a.d * b.ny - b.d * a.ny) / det, (a.nx * b.d - b.nx * a.d) / det};
}

/// The mean scan: each beam's reading averaged over the scans that have it (beams with a return
/// in more than 40 % of the scans), as a point.
Points meanScan(const lidarcal::io::Sequence& seq) {
  std::map<int, std::array<double, 3>> acc;  // beam -> sum angle, sum range, count
  for (const auto& h : seq.scans) {
    const lidarcal::io::Scan s = lidarcal::io::readScan(h.path);
    for (std::size_t b = 0; b < s.cloud->size(); ++b) {
      const auto& q = (*s.cloud)[b];
      if (!std::isfinite(q.x)) continue;
      auto& a = acc[static_cast<int>(b)];
      a[0] += std::atan2(q.y, q.x);
      a[1] += std::hypot(q.x, q.y);
      a[2] += 1;
    }
  }
  Points p;
  for (const auto& [b, a] : acc)
    if (a[2] > 0.4 * static_cast<double>(seq.scans.size()))
      p[b] = {a[1] / a[2] * std::cos(a[0] / a[2]), a[1] / a[2] * std::sin(a[0] / a[2])};
  return p;
}

/// The plan's walls as lines fitted to the mean scan (beam ranges in the header comment).
struct Walls {
  Line top, left, cabinet, bottom;
  Line right_free;  ///< fitted on its own
  Line right;       ///< parallel to the left wall
};

Walls fitWalls(const Points& p) {
  Walls w;
  w.top = fit(p, 28, 68);
  w.left = fit(p, 108, 135);
  w.cabinet = fit(p, 290, 325);
  w.bottom = fit(p, 205, 260);
  w.right_free = fit(p, 339, 350);
  w.right = fit(p, 339, 350, &w.left);
  return w;
}

void printWalls(const Walls& w) {
  auto show = [](const char* name, const Line& l) {
    std::printf("| %s | %.2f | %.4f | %d | %.1f |\n", name, std::atan2(l.ny, l.nx) * 180.0 / M_PI,
                l.d, l.n, 1000 * l.rms);
  };
  std::printf("Wall lines fitted to the mean scan (readings as the lidar gives them):\n\n");
  std::printf(
      "| wall | normal [deg] | distance from the lidar [m] | beams | RMS [mm] "
      "|\n|---|---|---|---|---|\n");
  show("top (south-west)", w.top);
  show("left (south-east)", w.left);
  show("right, free", w.right_free);
  show("right, parallel to left", w.right);
  show("cabinet face", w.cabinet);
  show("bottom side", w.bottom);
}

/// One of the laser-meter lines 1-5: parallel to the top wall at `from_top` from it, from the
/// left wall to `far`.
struct Ref {
  int line;
  double from_top, reference, authors;
  const Line* far;
};

std::vector<Ref> references(const Walls& w) {
  return {{1, 0.15, 6.155, 6.19522848, &w.right},
          {2, 0.55, 6.150, 6.18926752, &w.right},
          {3, 1.30, 6.147, 6.17809073, &w.right},
          {4, 1.50, 5.709, 5.77009549, &w.cabinet},
          {5, 2.30, 5.709, 5.77055445, &w.cabinet}};
}

/// The measurement line `r` in the scan: parallel to the top wall at its distance from it.
Line measurementLine(const Walls& w, const Ref& r) {
  return Line{w.top.nx, w.top.ny, w.top.d - r.from_top, 0, 0};
}

/// The errors of lines 1-5 in the scan and in the authors' lidar, against the laser meter.
struct Errors {
  std::vector<double> err;
  double sum = 0, sum_authors = 0;
};

Errors printReferenceLines(const Walls& w, const std::vector<Ref>& refs) {
  std::printf(
      "\n| line | from the top wall [m] | laser meter [m] | lidar, this scan [m] | error [m] | "
      "authors' lidar [m] | authors' error [m] |\n"
      "|---|---|---|---|---|---|---|\n");
  Errors e;
  for (const auto& r : refs) {
    const Line m = measurementLine(w, r);
    const auto u = intersect(m, w.left), v = intersect(m, *r.far);
    const double wall_to_wall = std::hypot(u.first - v.first, u.second - v.second);
    e.err.push_back(wall_to_wall - r.reference);
    e.sum += wall_to_wall - r.reference;
    e.sum_authors += r.authors - r.reference;
    std::printf("| %d | %.2f | %.3f | %.4f | %+.4f | %.4f | %+.4f |\n", r.line, r.from_top,
                r.reference, wall_to_wall, wall_to_wall - r.reference, r.authors,
                r.authors - r.reference);
  }
  return e;
}

/// Line 6 crosses the room from the top wall to the bottom side, near the right wall.
void printLine6(const Walls& w) {
  const Line &top = w.top, &bottom = w.bottom;
  const auto c = intersect(top, w.right), l = intersect(top, w.left);
  const double ux = (l.first - c.first) / std::hypot(l.first - c.first, l.second - c.second),
               uy = (l.second - c.second) / std::hypot(l.first - c.first, l.second - c.second);
  const double px = c.first + 0.60 * ux, py = c.second + 0.60 * uy;
  const double t =
      (bottom.d - (bottom.nx * px + bottom.ny * py)) / (bottom.nx * -top.nx + bottom.ny * -top.ny);
  std::printf("| 6 | (0.60 from the right wall) | 4.777 | %.4f | %+.4f | 4.8096 | +0.0396 |\n", t,
              t - 4.777);
}

/// The data files of the plot in `dir`: the mean scan, the wall lines, the measurement lines.
void writePlotData(const std::string& dir, const Points& p, const Walls& w,
                   const std::vector<Ref>& refs) {
  std::ofstream pts(dir + "/rplidar_mean_scan.dat"), lines(dir + "/rplidar_lines.dat"),
      meas(dir + "/rplidar_measurements.dat");
  for (const auto& [b, q] : p) pts << q.first << ' ' << q.second << ' ' << b << '\n';
  auto segment = [&](const Line& wall, int lo, int hi) {
    // The line between the beams lo and hi (where they meet it).
    for (int b : {lo, hi}) {
      const double a = p.count(b) ? std::atan2(p.at(b).second, p.at(b).first) : 0.0;
      const double r = wall.d / (wall.nx * std::cos(a) + wall.ny * std::sin(a));
      lines << r * std::cos(a) << ' ' << r * std::sin(a) << '\n';
    }
    lines << "\n\n";
  };
  segment(w.top, 28, 68);
  segment(w.left, 108, 135);
  segment(w.right, 339, 350);
  segment(w.cabinet, 290, 325);
  segment(w.bottom, 205, 260);
  for (const auto& r : refs) {
    const Line m = measurementLine(w, r);
    const auto u = intersect(m, w.left), v = intersect(m, *r.far);
    meas << u.first << ' ' << u.second << '\n' << v.first << ' ' << v.second << "\n\n\n";
  }
}

/// DIR/rplidar_walls.png with gnuplot, from the data files writePlotData wrote.
void drawPlot(const std::string& dir) {
  std::ofstream gp(dir + "/rplidar_walls.gp");
  gp << "set terminal pngcairo size 900,900 font \"DejaVu Sans,10\"\nset output "
        "\"rplidar_walls.png\"\nset size ratio -1\nset grid\n"
        "set title \"RPLIDAR A2 room: mean scan, wall lines, laser-meter lines 1-5\"\nset xlabel "
        "\"x [m]\"\nset ylabel \"y [m]\"\n"
        "plot \"rplidar_mean_scan.dat\" using 1:2 with points pt 7 ps 0.4 lc rgb \"#777777\" "
        "title \"mean reading per beam\", "
        "\"rplidar_lines.dat\" using 1:2 with lines lw 3 lc rgb \"#0077bb\" title \"wall lines "
        "(top, left, right, cabinet, bottom)\", "
        "\"rplidar_measurements.dat\" using 1:2 with lines lw 1 dt 2 lc rgb \"#cc3311\" title "
        "\"measurement lines 1-5\", "
        "\"<echo 0 0\" using 1:2 with points pt 9 ps 2 lc rgb \"black\" title \"lidar\"\n";
  gp.close();
  const std::string cmd = "cd '" + dir + "' && gnuplot rplidar_walls.gp";
  if (std::system(cmd.c_str()) != 0) std::fprintf(stderr, "gnuplot failed\n");
}

/// The mean error of lines 1-5 and the range offset it implies.
void printOffset(const Errors& e, std::size_t lines) {
  const double mean = e.sum / static_cast<double>(lines);
  double var = 0;
  for (double x : e.err) var += (x - mean) * (x - mean) / static_cast<double>(e.err.size() - 1);
  std::printf(
      "\nLines 1-5: mean wall-to-wall error %+.4f m (sd %.4f m), authors %+.4f m. A wall-to-wall "
      "distance holds two\n"
      "readings, so a constant range offset alpha_0 = %+.4f m +- %.4f m (standard error of the "
      "mean / 2).\n",
      mean, std::sqrt(var), e.sum_authors / static_cast<double>(lines), mean / 2.0,
      std::sqrt(var / static_cast<double>(e.err.size())) / 2.0);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace lidarcal;
  if (argc < 2) {
    std::fprintf(stderr, "usage: rplidar_reference SEQ (the imported rplidar_1.bag)\n");
    return 2;
  }
  const io::Sequence seq = io::openSequence(argv[1]);
  const Points p = meanScan(seq);
  const Walls walls = fitWalls(p);
  printWalls(walls);
  const std::vector<Ref> refs = references(walls);
  const Errors errors = printReferenceLines(walls, refs);
  printLine6(walls);
  if (argc >= 4 && std::string(argv[2]) == "--plot") {
    writePlotData(argv[3], p, walls, refs);
    drawPlot(argv[3]);
  }
  printOffset(errors, refs.size());
  return 0;
}
