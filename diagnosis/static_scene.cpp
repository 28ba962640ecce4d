#include "diagnosis/static_scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <cstdio>
#include <set>
#include <stdexcept>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>

#include "common/plural.hpp"
#include "diagnosis/skeleton.hpp"
#include "diagnosis/stats.hpp"
#include "diagnosis/tails.hpp"
#include "common/pose2.hpp"
#include "common/rng.hpp"
#include "common/stats_util.hpp"
#include "simulation/simulator.hpp"

namespace lidarcal::diagnosis {
namespace {

// ---------------------------------------------------------------------------------------------
// Direction bins: a beam over the scans.

struct Bin {
  int window = 0;                   ///< window of scans it belongs to (0 when the whole recording is one pose)
  double angle = 0.0;               ///< mean angle of its readings
  std::vector<std::size_t> idx;     ///< its readings
  bool slope = false;               ///< the angle varies within the bin (irregular beam grids)
  int wall = -1;                    ///< wall line it lies on, -1 none
  bool edge = false;                ///< next to a depth discontinuity
  double near = 0.0, far = 0.0;     ///< at an edge: the depths on both sides
  double cos_inc = 1.0;             ///< cosine of the incidence (1 when unknown)
  bool inc_known = false;
  double intensity = kNaN;          ///< geometric mean intensity of its readings (NaN: none recorded)
  double dark = 0.0;                ///< darkness ln(I_median / I) against the median bin's intensity (0: none recorded)
};

/// Per-bin location fitted on a subset of the scans.
struct BinFit {
  double m = 0.0, g = 0.0, abar = 0.0, med = 0.0, s2 = 0.0;
  double h = 0.0, tbar = 0.0;  ///< time trend (windows: the sensor creeping), metres per scan
  double n = 0.0;
  /// Location of a reading at angle a in scan t.
  double at(double a, double t) const { return m + g * (a - abar) + h * (t - tbar); }
};

struct Data {
  std::vector<double> a, y, t;  // angle, reading, scan
  std::vector<Bin> bins;
  std::vector<int> bin_of;      // reading -> bin (-1: not used)
  double width = 0.0;           // bin width (0: fixed grid)
  bool trend = false;           // windows: each bin has a time trend
  double t_mean = 0.0;
  double window_min = 0.0, window_max = 1.0;
  bool intensity = false;       // the bins carry an intensity
  double i_ref = kNaN;          // the median bin's intensity (the darkness reference; NaN: none recorded)
  std::vector<double> y_cell;   // dequantised data: the reading each y was spread from (its grid cell's centre)
};

/// Calls fn(i, bin, fit) for every reading i in a bin that has a location fit, in reading order.
template <class Fn>
void forEachFitted(const Data& d, const std::vector<BinFit>& f, Fn fn) {
  for (std::size_t i = 0; i < d.y.size(); ++i) {
    const int bi = d.bin_of[i];
    if (bi < 0 || f[static_cast<std::size_t>(bi)].n == 0) continue;
    fn(i, d.bins[static_cast<std::size_t>(bi)], f[static_cast<std::size_t>(bi)]);
  }
}

/// Geometric mean of the readings' intensities (those above zero; NaN when none).
double meanIntensity(const StaticScans& s, const std::vector<std::size_t>& idx) {
  double sum = 0.0, n = 0.0;
  for (std::size_t i : idx) {
    const double v = s.readings[i].intensity;
    if (!(v > 0.0) || !std::isfinite(v)) continue;
    sum += std::log(v);
    n += 1.0;
  }
  return n > 0.0 ? std::exp(sum / n) : kNaN;
}

/// Mean scan index of the binned readings (the drift's centre).
void setMeanTime(Data& d) {
  double tw = 0.0;
  std::size_t used = 0;
  for (std::size_t i = 0; i < d.t.size(); ++i)
    if (d.bin_of[i] >= 0) {
      tw += d.t[i];
      ++used;
    }
  d.t_mean = used ? tw / static_cast<double>(used) : 0.0;
}

/// Each bin's darkness against the median bin's intensity (upper median of the log intensities).
void setDarkness(Data& d) {
  std::vector<double> log_i;
  for (const Bin& b : d.bins)
    if (std::isfinite(b.intensity)) log_i.push_back(std::log(b.intensity));
  if (log_i.empty()) return;
  const double med = upperMedian(log_i);
  d.i_ref = std::exp(med);
  for (Bin& b : d.bins)
    if (std::isfinite(b.intensity)) b.dark = med - std::log(b.intensity);
}

/// Whether the bins' intensities vary (3 bins or more over 10 % from the median): a dark
/// surface can show. Not with one recorded value (the RPLIDAR's constant 47) or none.
bool darknessVaries(const Data& d) {
  if (!d.intensity) return false;
  std::size_t away = 0;
  for (const Bin& b : d.bins) away += std::abs(b.dark) > 0.1;
  return away >= 3;
}

Data makeBins(const StaticScans& s, std::size_t window) {
  Data d;
  const std::size_t n = s.readings.size();
  d.a.resize(n);
  d.y.resize(n);
  d.t.resize(n);
  double ymax = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    d.a[i] = wrapAngle(s.readings[i].angle_rad);
    d.y[i] = s.readings[i].range_m;
    d.t[i] = static_cast<double>(s.readings[i].scan);
    ymax = std::max(ymax, d.y[i]);
  }
  d.window_min = s.range_min_m;
  d.window_max = s.range_max_m < 1e8 ? s.range_max_m : 1.25 * ymax;
  // A fixed beam grid (the same angles every scan) bins by angle exactly; otherwise bins as
  // wide as the median beam spacing, with a linear trend in angle inside each.
  std::set<long long> angles;
  for (std::size_t i = 0; i < n; ++i) angles.insert(std::llround(d.a[i] * 1e7));
  const double beams = s.beams_per_scan > 0 ? static_cast<double>(s.beams_per_scan) : 360.0;
  const bool exact = static_cast<double>(angles.size()) <= 1.5 * beams;
  if (!exact) d.width = 2.0 * kPi / beams;
  d.trend = window > 0;
  // Key: (window, angle).
  std::map<std::pair<long long, long long>, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < n; ++i) {
    const long long w = window > 0 ? static_cast<long long>(s.readings[i].scan / window) : 0;
    const long long a = exact ? std::llround(d.a[i] * 1e7) : static_cast<long long>(std::floor((d.a[i] + kPi) / d.width));
    groups[{w, a}].push_back(i);
  }
  const std::size_t scans_per_bin = window > 0 ? window : s.scans;
  const std::size_t min_n = window > 0 ? std::max<std::size_t>(5, (3 * window) / 4) : std::max<std::size_t>(8, s.scans / 10);
  d.bin_of.assign(n, -1);
  for (auto& [key, idx] : groups) {
    if (idx.size() < min_n) continue;
    (void)scans_per_bin;
    Bin b;
    b.window = static_cast<int>(key.first);
    double lo = kInf, hi = -kInf, sum = 0.0;
    for (std::size_t i : idx) {
      sum += d.a[i];
      lo = std::min(lo, d.a[i]);
      hi = std::max(hi, d.a[i]);
    }
    b.angle = sum / static_cast<double>(idx.size());
    b.slope = hi - lo > 1e-6;
    b.idx = std::move(idx);
    if (s.has_intensity) b.intensity = meanIntensity(s, b.idx);
    for (std::size_t i : b.idx) d.bin_of[i] = static_cast<int>(d.bins.size());
    d.bins.push_back(std::move(b));
  }
  setMeanTime(d);
  d.intensity = s.has_intensity;
  setDarkness(d);
  return d;
}

/// A reading this far from its beam's median, and six robust deviations, lies on another surface.
constexpr double kSceneStepM = 0.05;

/// A normal sample's standard deviation over its median absolute deviation.
constexpr double kMadToSigma = 1.4826;
/// Least beam sector the wall lines must cover (summed over lines) for a static diagnosis: the
/// Hokuyo range sweep's reflector fills 2-5 degrees; the sparsest real room here (the YDLIDAR X4,
/// three walls of 8-12 returning beams) 14.8-19.8.
constexpr double kMinWallSectorRad = deg2rad(10.0);

/// Whether bin b saw the scene change: its readings off its median (by kSceneStepM and six
/// robust deviations) come in runs in time, as when an object is moved into or out of the beam
/// or a person walks through it, not scattered over the recording as a sensor's own outliers
/// and mixed pixels are. Wald-Wolfowitz runs test on the off/on labels in scan order (z < -4),
/// with at least 5 off readings and 5 % of the bin's.
bool sceneChanged(const Data& d, const Bin& b) {
  std::vector<double> ys;
  for (std::size_t i : b.idx) ys.push_back(d.y[i]);
  const double med = upperMedian(ys);
  std::vector<double> dev;
  for (double y : ys) dev.push_back(std::abs(y - med));
  const double step = std::max(kSceneStepM, 6.0 * kMadToSigma * upperMedian(dev));
  std::vector<std::pair<double, bool>> seq;  // (scan, off)
  for (std::size_t i : b.idx) seq.emplace_back(d.t[i], std::abs(d.y[i] - med) > step);
  std::stable_sort(seq.begin(), seq.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  const auto n = static_cast<double>(seq.size());
  double off = 0.0, runs = seq.empty() ? 0.0 : 1.0;
  for (std::size_t k = 0; k < seq.size(); ++k) {
    off += seq[k].second ? 1.0 : 0.0;
    if (k > 0 && seq[k].second != seq[k - 1].second) runs += 1.0;
  }
  const double on = n - off;
  if (off < 5.0 || off < 0.05 * n || on < 5.0) return false;
  const double mean = 1.0 + 2.0 * off * on / n;
  const double var = 2.0 * off * on * (2.0 * off * on - n) / (n * n * (n - 1.0));
  return var > 0.0 && (runs - mean) / std::sqrt(var) < -4.0;
}

/// Drops the bins that saw the scene change (sceneChanged) when they are at most half the bins
/// (beyond that the sensor, not the scene, moved; movedFraction has already looked at the
/// medians); returns how many were dropped. In the forklift recordings a third of the beams see
/// objects carried in or out.
std::size_t dropChangedBins(Data& d) {
  std::vector<bool> drop(d.bins.size());
  std::size_t changed = 0;
  for (std::size_t b = 0; b < d.bins.size(); ++b) changed += (drop[b] = sceneChanged(d, d.bins[b])) ? 1 : 0;
  if (changed == 0 || static_cast<double>(changed) > 0.5 * static_cast<double>(d.bins.size())) return 0;
  std::vector<Bin> kept;
  d.bin_of.assign(d.y.size(), -1);
  for (std::size_t b = 0; b < d.bins.size(); ++b) {
    if (drop[b]) continue;
    for (std::size_t i : d.bins[b].idx) d.bin_of[i] = static_cast<int>(kept.size());
    kept.push_back(std::move(d.bins[b]));
  }
  d.bins = std::move(kept);
  setMeanTime(d);
  setDarkness(d);  // against the median of the bins kept
  return changed;
}

/// Location of every bin from the readings with train[scan] (all when empty), after removing
/// a drift c (t - t_mean): mean, and linear terms in angle (irregular grids) and time (windows).
std::vector<BinFit> fitBins(const Data& d, const std::vector<bool>& train, double drift) {
  std::vector<BinFit> out(d.bins.size());
  std::vector<double> ys;
  for (std::size_t b = 0; b < d.bins.size(); ++b) {
    const Bin& bin = d.bins[b];
    BinFit& f = out[b];
    double sa = 0.0, st = 0.0, n = 0.0;
    ys.clear();
    for (std::size_t i : bin.idx) {
      if (!train.empty() && !train[static_cast<std::size_t>(d.t[i])]) continue;
      sa += d.a[i];
      st += d.t[i];
      n += 1.0;
      ys.push_back(d.y[i] - drift * (d.t[i] - d.t_mean));
    }
    const int p = 1 + (bin.slope ? 1 : 0) + (d.trend ? 1 : 0);
    if (n < static_cast<double>(p) + 2.0) {
      f.n = 0.0;
      continue;
    }
    f.n = n;
    f.abar = sa / n;
    f.tbar = st / n;
    // Least squares in the centred columns [1, a - abar, t - tbar].
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d aty = Eigen::Vector3d::Zero();
    std::size_t k = 0;
    for (std::size_t i : bin.idx) {
      if (!train.empty() && !train[static_cast<std::size_t>(d.t[i])]) continue;
      const Eigen::Vector3d x(1.0, bin.slope ? d.a[i] - f.abar : 0.0, d.trend ? d.t[i] - f.tbar : 0.0);
      ata += x * x.transpose();
      aty += x * ys[k++];
    }
    for (int j = 0; j < 3; ++j)
      if (ata(j, j) <= 0.0) ata(j, j) = 1.0;
    const Eigen::Vector3d c = ata.ldlt().solve(aty);
    f.m = c(0);
    f.g = c(1);
    f.h = c(2);
    f.med = upperMedian(ys);
    double ss = 0.0;
    k = 0;
    for (std::size_t i : bin.idx) {
      if (!train.empty() && !train[static_cast<std::size_t>(d.t[i])]) continue;
      const double r = ys[k++] - f.at(d.a[i], d.t[i]);
      ss += r * r;
    }
    f.s2 = ss / std::max(n - static_cast<double>(p), 1.0);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Walls: straight runs of bin means (split and merge), incidences, depth discontinuities.

struct Line {
  double theta = 0.0, p = 0.0;  // normal direction and distance: x cos(theta) + y sin(theta) = p
};

Line fitLine(const std::vector<Eigen::Vector2d>& pts) {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& q : pts) c += q;
  c /= static_cast<double>(pts.size());
  Eigen::Matrix2d s = Eigen::Matrix2d::Zero();
  for (const auto& q : pts) s += (q - c) * (q - c).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(s);
  Eigen::Vector2d nrm = es.eigenvectors().col(0);  // smallest eigenvalue: the normal
  double p = nrm.dot(c);
  if (p < 0) {
    nrm = -nrm;
    p = -p;
  }
  return Line{std::atan2(nrm.y(), nrm.x()), p};
}

double lineDistance(const Line& l, const Eigen::Vector2d& q) {
  return q.x() * std::cos(l.theta) + q.y() * std::sin(l.theta) - l.p;
}

/// The bin mean's point in the sensor frame.
Eigen::Vector2d binPoint(const Data& d, const std::vector<BinFit>& f, std::size_t b) {
  return Eigen::Vector2d(f[b].m * std::cos(d.bins[b].angle), f[b].m * std::sin(d.bins[b].angle));
}

/// Bins by window, then by angle.
std::vector<std::size_t> binOrder(const Data& d) {
  std::vector<std::size_t> order(d.bins.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return d.bins[a].window != d.bins[b].window ? d.bins[a].window < d.bins[b].window : d.bins[a].angle < d.bins[b].angle;
  });
  return order;
}

/// Angular step between neighbouring bins: the bin width, else the median gap.
double binStep(const Data& d, const std::vector<std::size_t>& order) {
  if (d.width > 0.0) return d.width;
  std::vector<double> gaps;
  for (std::size_t k = 1; k < order.size(); ++k) gaps.push_back(d.bins[order[k]].angle - d.bins[order[k - 1]].angle);
  return gaps.empty() ? deg2rad(1.0) : upperMedian(gaps);
}

/// Runs: neighbours in angle whose points are close (no depth jump, no missing beam between).
/// Marks the bins on both sides of a depth discontinuity as edges.
std::vector<std::vector<std::size_t>> findRuns(Data& d, const std::vector<BinFit>& f, const std::vector<std::size_t>& order,
                                               double step) {
  std::vector<std::vector<std::size_t>> runs;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t b = order[k];
    if (f[b].n == 0) continue;
    bool joins = false;
    if (!runs.empty() && d.bins[runs.back().back()].window == d.bins[b].window) {
      const std::size_t prev = runs.back().back();
      const double da = d.bins[b].angle - d.bins[prev].angle;
      const double gap = (binPoint(d, f, b) - binPoint(d, f, prev)).norm();
      joins = da <= 2.5 * step && gap <= std::max(0.15, 4.0 * f[b].m * da);
      if (!joins && da <= 2.5 * step && std::abs(f[b].m - f[prev].m) > 0.05) {
        // A depth discontinuity between neighbouring beams: both sides may see mixed pixels.
        for (std::size_t e : {b, prev}) {
          d.bins[e].edge = true;
          d.bins[e].near = std::min(f[b].m, f[prev].m);
          d.bins[e].far = std::max(f[b].m, f[prev].m);
        }
      }
    }
    if (joins) runs.back().push_back(b);
    else runs.push_back({b});
  }
  return runs;
}

/// Incidence from the local slope of the means (any surface): tan(phi) = |dm / da| / m.
void setIncidences(Data& d, const std::vector<BinFit>& f, const std::vector<std::vector<std::size_t>>& runs) {
  for (const auto& run : runs) {
    for (std::size_t k = 0; k < run.size(); ++k) {
      if (run.size() < 3) break;
      const std::size_t lo = run[k == 0 ? 0 : k - 1], hi = run[k + 1 == run.size() ? k : k + 1];
      const double da = d.bins[hi].angle - d.bins[lo].angle;
      if (!(da > 0.0)) continue;
      const double slope = (f[hi].m - f[lo].m) / da;
      Bin& b = d.bins[run[k]];
      b.cos_inc = 1.0 / std::sqrt(1.0 + std::pow(slope / f[run[k]].m, 2));
      b.inc_known = true;
    }
  }
}

/// Split and merge each run into straight pieces (deviation <= 2.5 cm), at least 8 bins.
std::vector<std::vector<std::size_t>> straightPieces(const Data& d, const std::vector<BinFit>& f,
                                                     const std::vector<std::vector<std::size_t>>& runs) {
  std::vector<std::vector<std::size_t>> pieces;
  std::vector<std::pair<std::size_t, std::size_t>> stack;
  for (const auto& run : runs) {
    std::vector<std::size_t> inner(run.begin(), run.end());
    // The outermost bins of a run border a discontinuity or a gap: not part of a wall.
    if (inner.size() >= 3) inner = std::vector<std::size_t>(run.begin() + 1, run.end() - 1);
    if (inner.size() < 8) continue;
    stack.push_back({0, inner.size()});
    while (!stack.empty()) {
      const auto [lo, hi] = stack.back();
      stack.pop_back();
      if (hi - lo < 8) continue;
      std::vector<Eigen::Vector2d> pts;
      for (std::size_t k = lo; k < hi; ++k) pts.push_back(binPoint(d, f, inner[k]));
      const Line l = fitLine(pts);
      double worst = 0.0;
      std::size_t at = lo;
      for (std::size_t k = lo; k < hi; ++k) {
        const double dev = std::abs(lineDistance(l, pts[k - lo]));
        if (dev > worst) {
          worst = dev;
          at = k;
        }
      }
      if (worst <= 0.025) {
        pieces.push_back(std::vector<std::size_t>(inner.begin() + static_cast<long>(lo), inner.begin() + static_cast<long>(hi)));
      } else {
        const std::size_t cut = std::clamp(at, lo + 1, hi - 1);
        stack.push_back({cut, hi});
        stack.push_back({lo, cut});
      }
    }
  }
  return pieces;
}

/// Finds the walls among the bins (fills wall, edge, near/far, incidence) from full-data means.
std::vector<Line> findWalls(Data& d, const std::vector<BinFit>& f) {
  const std::vector<std::size_t> order = binOrder(d);
  const auto runs = findRuns(d, f, order, binStep(d, order));
  setIncidences(d, f, runs);
  std::vector<Line> lines;
  for (const auto& piece : straightPieces(d, f, runs)) {
    std::vector<Eigen::Vector2d> pts;
    for (std::size_t b : piece) pts.push_back(binPoint(d, f, b));
    const Line l = fitLine(pts);
    const int w = static_cast<int>(lines.size());
    lines.push_back(l);
    for (std::size_t b : piece) {
      d.bins[b].wall = w;
      d.bins[b].cos_inc = std::abs(std::cos(d.bins[b].angle - l.theta));
      d.bins[b].inc_known = true;
    }
  }
  return lines;
}

// ---------------------------------------------------------------------------------------------
// The wall model: bin means on walls = alpha_0 + b (1 - cos phi) + p / cos(a - theta), with
// roughness tau. Gauss-Newton; leave-one-bin-out predictive log-likelihoods.

struct WallFit {
  double alpha0 = 0.0, b = 0.0, tau = 0.0;
  double alpha0_se = kInf, b_se = kInf;
  std::vector<Line> lines;
  std::vector<double> loo_ll;    ///< per wall bin (order of `bins` below)
  double in_ll = 0.0;            ///< in-sample log-likelihood of the wall bins' means
  std::vector<std::size_t> bins;  ///< the wall bins
  std::vector<double> resid;     ///< bin mean minus model, per wall bin
  double rms = 0.0;
  bool ok = false;
};

/// The wall model's mean of bin b (u: beam angle from the wall's normal, cu: its cosine, held
/// away from 0).
double wallMean(const Data& d, const WallFit& w, std::size_t b, double& u, double& cu) {
  const Line& l = w.lines[static_cast<std::size_t>(d.bins[b].wall)];
  u = d.bins[b].angle - l.theta;
  cu = std::max(std::cos(u), 0.05);
  return w.alpha0 + w.b * (1.0 - cu) + l.p / cu;
}

/// The wall model's least-squares system at its current parameters: Jacobian (alpha_0, b when
/// fitted, then p and theta of each line), residuals and weights of the wall bins.
struct WallSystem {
  Eigen::SparseMatrix<double, Eigen::RowMajor> j;  ///< four entries a row at most: the normal matrix is an arrow
  Eigen::VectorXd r, wt;
};

/// The weighted normal matrix J^T W J (alpha_0 held: its diagonal set to `held_diagonal`).
Eigen::SparseMatrix<double> wallNormal(const WallSystem& s, bool alpha0_free, double held_diagonal) {
  const Eigen::SparseMatrix<double, Eigen::RowMajor> jw = s.wt.asDiagonal() * s.j;
  Eigen::SparseMatrix<double> h = Eigen::SparseMatrix<double>(s.j.transpose()) * Eigen::SparseMatrix<double>(jw);
  if (!alpha0_free) h.coeffRef(0, 0) = held_diagonal;
  return h;
}

/// Residuals and weights of the wall bins (roughness tau2 plus the bin mean's variance).
void wallResiduals(const Data& d, const std::vector<BinFit>& f, const WallFit& w, double tau2, WallSystem& s) {
  for (int k = 0; k < static_cast<int>(w.bins.size()); ++k) {
    const std::size_t b = w.bins[static_cast<std::size_t>(k)];
    double u, cu;
    s.r(k) = f[b].m - wallMean(d, w, b, u, cu);
    s.wt(k) = 1.0 / (tau2 + f[b].s2 / f[b].n);
  }
}

/// Gauss-Newton on the wall model at fixed roughness (at most 15 steps); false when a step is
/// not finite.
bool wallGaussNewton(const Data& d, const std::vector<BinFit>& f, WallFit& w, bool with_b, bool alpha0_free, double tau2,
                     WallSystem& s) {
  const int nb = static_cast<int>(w.bins.size()), nl = static_cast<int>(w.lines.size());
  std::vector<Eigen::Triplet<double>> entries;
  for (int it = 0; it < 15; ++it) {
    entries.clear();
    for (int k = 0; k < nb; ++k) {
      const std::size_t b = w.bins[static_cast<std::size_t>(k)];
      double u, cu;
      const double mu = wallMean(d, w, b, u, cu);
      const Line& l = w.lines[static_cast<std::size_t>(d.bins[b].wall)];
      s.r(k) = f[b].m - mu;
      s.wt(k) = 1.0 / (tau2 + f[b].s2 / f[b].n);
      if (alpha0_free) entries.emplace_back(k, 0, 1.0);
      int c = 1;
      if (with_b) entries.emplace_back(k, c++, 1.0 - cu);
      const int wl = c + 2 * d.bins[b].wall;
      entries.emplace_back(k, wl, 1.0 / cu);
      entries.emplace_back(k, wl + 1, -l.p * std::sin(u) / (cu * cu) - w.b * std::sin(u));
    }
    s.j.setFromTriplets(entries.begin(), entries.end());
    // Sparse: a cluttered room has hundreds of short lines, and a dense normal matrix then
    // costs seconds a step (the forklift's 1081-beam scans).
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(wallNormal(s, alpha0_free, 1.0));
    if (ldlt.info() != Eigen::Success) return false;
    const Eigen::VectorXd step = ldlt.solve(Eigen::VectorXd(s.j.transpose() * s.wt.cwiseProduct(s.r)));
    if (!step.allFinite()) return false;
    w.alpha0 += step(0);
    int c = 1;
    if (with_b) w.b += step(c++);
    for (int l = 0; l < nl; ++l) {
      w.lines[static_cast<std::size_t>(l)].p += step(c + 2 * l);
      w.lines[static_cast<std::size_t>(l)].theta += step(c + 2 * l + 1);
    }
    if (step.cwiseAbs().maxCoeff() < 1e-9) break;
  }
  return true;
}

/// Roughness: ML of tau^2 given the residuals (ternary search on log tau).
double wallRoughness(const std::vector<BinFit>& f, const WallFit& w, const Eigen::VectorXd& r) {
  auto ll = [&](double log_tau) {
    const double t2 = std::exp(2.0 * log_tau);
    double s = 0.0;
    for (int k = 0; k < static_cast<int>(w.bins.size()); ++k) {
      const std::size_t b = w.bins[static_cast<std::size_t>(k)];
      const double v = t2 + f[b].s2 / f[b].n;
      s -= 0.5 * (std::log(v) + r(k) * r(k) / v);
    }
    return s;
  };
  const double lt = ternaryMax(ll, std::log(1e-5), std::log(0.5), 60);
  return std::exp(2.0 * lt);
}

/// Final residuals, standard errors and leave-one-out predictive log-likelihoods (the
/// Jacobian is the last Gauss-Newton step's).
void finishWalls(const Data& d, const std::vector<BinFit>& f, WallFit& w, bool with_b, bool alpha0_free, double tau2,
                 WallSystem& s) {
  const int nb = static_cast<int>(w.bins.size());
  const auto np = static_cast<int>(s.j.cols());
  wallResiduals(d, f, w, tau2, s);
  // alpha_0 held: no uncertainty, no leverage
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(wallNormal(s, alpha0_free, 1e12));
  if (ldlt.info() != Eigen::Success) return;
  const Eigen::MatrixXd cov = ldlt.solve(Eigen::MatrixXd::Identity(np, np));
  w.alpha0_se = alpha0_free ? std::sqrt(std::max(cov(0, 0), 0.0)) : 0.0;
  if (with_b) w.b_se = std::sqrt(std::max(cov(1, 1), 0.0));
  w.loo_ll.resize(static_cast<std::size_t>(nb));
  w.resid.resize(static_cast<std::size_t>(nb));
  double ss = 0.0;
  for (int k = 0; k < nb; ++k) {
    double quad = 0.0;  // j_k^T cov j_k over the row's few entries
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator a(s.j, k); a; ++a)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator c(s.j, k); c; ++c)
        quad += a.value() * cov(a.col(), c.col()) * c.value();
    const double hii = std::min(s.wt(k) * quad, 0.99);
    const double v = (1.0 / s.wt(k)) / (1.0 - hii);
    const double e = s.r(k) / (1.0 - hii);
    w.loo_ll[static_cast<std::size_t>(k)] = -0.5 * (kLog2Pi + std::log(v) + e * e / v);
    w.in_ll -= 0.5 * (kLog2Pi - std::log(s.wt(k)) + s.r(k) * s.r(k) * s.wt(k));
    w.resid[static_cast<std::size_t>(k)] = s.r(k);
    ss += s.r(k) * s.r(k);
  }
  w.rms = std::sqrt(ss / nb);
  w.ok = true;
}

WallFit fitWalls(const Data& d, const std::vector<BinFit>& f, const std::vector<Line>& start, bool with_b,
                 double fixed_alpha0 = kNaN) {
  WallFit w;
  w.lines = start;
  const bool alpha0_free = !std::isfinite(fixed_alpha0);
  if (!alpha0_free) w.alpha0 = fixed_alpha0;
  for (std::size_t b = 0; b < d.bins.size(); ++b)
    if (d.bins[b].wall >= 0 && f[b].n > 0) w.bins.push_back(b);
  const int nl = static_cast<int>(start.size());
  const int np = 1 + (with_b ? 1 : 0) + 2 * nl;
  const int nb = static_cast<int>(w.bins.size());
  if (nl == 0 || nb < np + 3) return w;
  WallSystem s{Eigen::SparseMatrix<double, Eigen::RowMajor>(nb, np), Eigen::VectorXd(nb), Eigen::VectorXd(nb)};
  double tau2 = 1e-6;
  for (int outer = 0; outer < 4; ++outer) {
    if (!wallGaussNewton(d, f, w, with_b, alpha0_free, tau2, s)) return w;
    tau2 = wallRoughness(f, w, s.r);
  }
  w.tau = std::sqrt(tau2);
  finishWalls(d, f, w, with_b, alpha0_free, tau2, s);
  return w;
}


// ---------------------------------------------------------------------------------------------
// The reading model: readings of a bin around its location.

struct Model {
  double sigma_e = 0.01;   ///< scale of sigma = sigma_e |m|^kappa (1 / cos phi)^gamma (I_ref / I)^delta
  double kappa = 2.0;      ///< range exponent (seed 004: 2)
  double gamma = 0.0;      ///< incidence exponent
  double delta = 0.0;      ///< dark-surface exponent: sigma times (I_ref / I)^delta
  double drift = 0.0;      ///< metres per scan
  double mixed = 0.0;      ///< fraction of mixed readings at edge bins
  double dof = 0.0;        ///< Student t degrees of freedom (0: Gaussian)
  double q = 0.0;          ///< quantisation step (0: densities)
  bool robust_edges = false;  ///< edge bins centred on their median (mixed-pixel model)
};

struct Flags {
  bool kappa = false, gamma = false, drift = false, mixed = false, dof = false, quant = false, wall_b = false, delta = false;
  int parameters() const { return kappa + gamma + drift + mixed + dof + quant + wall_b + delta; }
};

Flags flagsOf(Effect e) {
  Flags f;
  if (e == Effect::range_noise_law) f.kappa = true;
  else if (e == Effect::incidence_noise) f.gamma = true;
  else if (e == Effect::range_drift) f.drift = true;
  else if (e == Effect::mixed_pixels) f.mixed = true;
  else if (e == Effect::heavy_tails) f.dof = true;
  else if (e == Effect::quantisation) f.quant = true;
  else if (e == Effect::incidence_bias) f.wall_b = true;
  else if (e == Effect::dark_surface) f.delta = true;
  return f;
}

double shapeOf(const Model& m, const Bin& b, double loc) {
  return std::pow(std::max(std::abs(loc), 1e-3), m.kappa) * incidenceNoiseFactor(m.gamma, b.cos_inc) *
         darkNoiseFactor(m.delta, b.dark);
}

double centreOf(const Model& m, const Bin& b, const BinFit& f) { return m.robust_edges && b.edge ? f.med : f.m; }

/// Where a reading at angle a in scan t is expected (without the drift term).
double expected(const Model& m, const Bin& b, const BinFit& f, double a, double t) {
  return f.at(a, t) + (centreOf(m, b, f) - f.m);
}

/// Log-likelihood of one reading (predictive: the bin's location is known to 1 / n_train).
double readingLL(const Model& m, const Data& d, const Bin& b, const BinFit& f, std::size_t i, double floor_weight) {
  const double centre = expected(m, b, f, d.a[i], d.t[i]) + m.drift * (d.t[i] - d.t_mean);
  const double sigma = std::max(m.sigma_e * shapeOf(m, b, centre) * std::sqrt(1.0 + 1.0 / std::max(f.n, 1.0)), 1e-6);
  const double y = d.y[i];
  const double z = (y - centre) / sigma;
  double dens;
  if (m.q > 0.0) {
    // Readings rounded to a grid q: the probability of the reading's cell [y - q/2, y + q/2]
    // under the unrounded noise, over q. That is the density of the reading plus a uniform
    // rounding error, so it compares like with like with the other models' densities; the
    // noise scale is the unrounded one (ModelFitter::fitCellScale), so the rounding's
    // variance is not counted twice.
    const double cell = d.y_cell.empty() ? y : d.y_cell[i];
    dens = normalMass(cell - 0.5 * m.q, cell + 0.5 * m.q, centre, sigma) / m.q;
  } else if (m.dof > 0.0) {
    const double nu = m.dof, s = sigma * std::sqrt((nu - 2.0) / nu), x = (y - centre) / s;
    dens = std::exp(std::lgamma(0.5 * (nu + 1.0)) - std::lgamma(0.5 * nu) - 0.5 * std::log(nu * kPi) -
                    0.5 * (nu + 1.0) * std::log1p(x * x / nu)) / s;
  } else {
    dens = std::exp(-0.5 * z * z) / (sigma * std::sqrt(2.0 * kPi));
  }
  double mix = 0.0;
  if (m.mixed > 0.0 && b.edge && b.far > b.near && y >= b.near && y <= b.far) mix = 1.0 / (b.far - b.near);
  const double window = d.window_max > d.window_min ? 1.0 / (d.window_max - d.window_min) : 0.0;
  const double total = (1.0 - floor_weight) * ((1.0 - m.mixed) * dens + m.mixed * mix) + floor_weight * window;
  return std::log(std::max(total, 1e-300));
}

/// Fits the free parameters of a reading model on the training scans' readings: the noise law
/// (profile likelihood on per-bin sums), drift, mixed-pixel fraction (EM), Student-t dof.
class ModelFitter {
 public:
  ModelFitter(const Data& d, const std::vector<bool>& train, const Flags& fl, std::vector<BinFit>& fits);
  Model fit(double q_detected);

 private:
  const Bin& binOf(std::size_t i) const { return d_.bins[static_cast<std::size_t>(d_.bin_of[i])]; }
  const BinFit& fitOf(std::size_t i) const { return fits_[static_cast<std::size_t>(d_.bin_of[i])]; }
  double residual(std::size_t i) const;
  double sigmaOf(std::size_t i) const { return m_.sigma_e * shapeOf(m_, binOf(i), centreOf(m_, binOf(i), fitOf(i))); }
  void refresh();
  double profile(const Model& t, double* sigma_e) const;
  /// profile() with one exponent of the noise law changed.
  template <class Set>
  double profileWith(Set set) const {
    Model t = m_;
    set(t);
    return profile(t, nullptr);
  }
  void dropOutliers();
  void fitDrift();
  void fitMixed();
  void fitDof();
  void fitCellScale();

  const Data& d_;
  const std::vector<bool>& train_;
  const Flags fl_;
  std::vector<BinFit>& fits_;
  Model m_;
  std::vector<std::size_t> use_;  // training readings in usable bins
  std::vector<double> weight_;    // 1 - mixed-pixel responsibility
  // The profile likelihood of the noise law works on per-bin sums (the law depends on the bin
  // only): refreshed whenever residuals or weights change.
  std::vector<double> bin_ss_, bin_n_;
};

ModelFitter::ModelFitter(const Data& d, const std::vector<bool>& train, const Flags& fl, std::vector<BinFit>& fits)
    : d_(d), train_(train), fl_(fl), fits_(fits), weight_(d.y.size(), 1.0), bin_ss_(d.bins.size()), bin_n_(d.bins.size()) {}

double ModelFitter::residual(std::size_t i) const {
  return d_.y[i] - expected(m_, binOf(i), fitOf(i), d_.a[i], d_.t[i]) - m_.drift * (d_.t[i] - d_.t_mean);
}

void ModelFitter::refresh() {
  std::fill(bin_ss_.begin(), bin_ss_.end(), 0.0);
  std::fill(bin_n_.begin(), bin_n_.end(), 0.0);
  for (std::size_t i : use_) {
    if (weight_[i] < 0.5) continue;
    const auto b = static_cast<std::size_t>(d_.bin_of[i]);
    const double r = residual(i);
    bin_ss_[b] += r * r;
    bin_n_[b] += 1.0;
  }
}

/// Profile log-likelihood of the noise law's exponents (sigma_e at its ML value).
double ModelFitter::profile(const Model& t, double* sigma_e) const {
  double s2 = 0.0, logh = 0.0, n = 0.0;
  for (std::size_t b = 0; b < d_.bins.size(); ++b) {
    if (bin_n_[b] == 0.0) continue;
    const double h = std::max(shapeOf(t, d_.bins[b], centreOf(t, d_.bins[b], fits_[b])), 1e-9);
    s2 += bin_ss_[b] / (h * h);
    logh += bin_n_[b] * std::log(h);
    n += bin_n_[b];
  }
  s2 /= std::max(n, 1.0);
  if (sigma_e) *sigma_e = std::sqrt(s2);
  return -0.5 * n * std::log(std::max(s2, 1e-300)) - logh;
}

/// Outliers beyond 6 sigma do not set the noise scale (they are the floor's business).
void ModelFitter::dropOutliers() {
  for (std::size_t i : use_) {
    const double s = sigmaOf(i);
    if (std::abs(residual(i)) > 6.0 * s) weight_[i] = 0.0;
    else if (!fl_.mixed) weight_[i] = 1.0;
  }
}

void ModelFitter::fitDrift() {
  double num = 0.0, den = 0.0;
  for (std::size_t i : use_) {
    const double s = sigmaOf(i);
    if (weight_[i] < 0.5) continue;
    const double x = d_.t[i] - d_.t_mean;
    num += x * (residual(i) + m_.drift * x) / (s * s);
    den += x * x / (s * s);
  }
  m_.drift = den > 0.0 ? num / den : 0.0;
  fits_ = fitBins(d_, train_, m_.drift);
  refresh();
  profile(m_, &m_.sigma_e);
}

/// One EM step of the mixed-pixel fraction at edge bins (readings between the two depths).
void ModelFitter::fitMixed() {
  if (m_.mixed <= 0.0) m_.mixed = 0.05;
  double sum = 0.0, n = 0.0;
  for (std::size_t i : use_) {
    const Bin& b = binOf(i);
    if (!b.edge) continue;
    const double s = sigmaOf(i);
    const double z = residual(i) / s;
    const double nd = std::exp(-0.5 * z * z) / (s * std::sqrt(2.0 * kPi));
    const double u = (b.far > b.near && d_.y[i] >= b.near && d_.y[i] <= b.far) ? 1.0 / (b.far - b.near) : 0.0;
    const double resp = m_.mixed * u / (m_.mixed * u + (1.0 - m_.mixed) * nd + 1e-300);
    weight_[i] = 1.0 - resp;
    sum += resp;
    n += 1.0;
  }
  m_.mixed = n > 0 ? std::clamp(sum / n, 1e-4, 0.9) : 0.0;
}

void ModelFitter::fitDof() {
  auto ll = [&](double log_nu) {
    Model t = m_;
    t.dof = 2.0 + std::exp(log_nu);
    double s = 0.0;
    for (std::size_t k = 0; k < use_.size(); k += std::max<std::size_t>(1, use_.size() / 20000)) {
      const std::size_t i = use_[k];
      s += readingLL(t, d_, binOf(i), fitOf(i), i, 0.0);
    }
    return s;
  };
  m_.dof = 2.0 + std::exp(ternaryMax(ll, std::log(0.1), std::log(300.0), 50));
}

/// sigma_e under the rounded model (readingLL: a normal cell probability per reading): the
/// Gaussian profile's sigma_e holds the rounding's variance too, the cells carry it now. ML over
/// the training readings the noise scale is fitted on (outliers beyond 6 sigma left out), about
/// their bin's location like the profile's (readingLL's widening for a held-out reading is not
/// applied: a training reading is part of its bin's mean).
void ModelFitter::fitCellScale() {
  std::vector<double> shape(use_.size()), centre(use_.size());
  for (std::size_t k = 0; k < use_.size(); ++k) {
    const std::size_t i = use_[k];
    centre[k] = expected(m_, binOf(i), fitOf(i), d_.a[i], d_.t[i]) + m_.drift * (d_.t[i] - d_.t_mean);
    shape[k] = shapeOf(m_, binOf(i), centreOf(m_, binOf(i), fitOf(i)));  // at the bin's location, as profile() takes it
  }
  auto ll = [&](double log_sigma) {
    const double se = std::exp(log_sigma);
    double s = 0.0;
    for (std::size_t k = 0; k < use_.size(); ++k) {
      const std::size_t i = use_[k];
      if (weight_[i] < 0.5) continue;
      const double sigma = std::max(se * shape[k], 1e-6);
      s += std::log(std::max(normalMass(d_.y[i] - 0.5 * m_.q, d_.y[i] + 0.5 * m_.q, centre[k], sigma), 1e-300));
    }
    return s;
  };
  const double top = std::log(std::max(m_.sigma_e, 1e-9));
  m_.sigma_e = std::exp(ternaryMax(ll, top - std::log(1000.0), top + std::log(1.2), 60));
}

Model ModelFitter::fit(double q_detected) {
  m_.robust_edges = fl_.mixed;
  if (fl_.quant) m_.q = q_detected;
  fits_ = fitBins(d_, train_, 0.0);
  for (std::size_t i = 0; i < d_.y.size(); ++i) {
    const int b = d_.bin_of[i];
    if (b < 0 || fits_[static_cast<std::size_t>(b)].n == 0) continue;
    if (!train_.empty() && !train_[static_cast<std::size_t>(d_.t[i])]) continue;
    use_.push_back(i);
  }
  for (int pass = 0; pass < 3; ++pass) {
    refresh();
    profile(m_, &m_.sigma_e);
    dropOutliers();
    refresh();
    if (fl_.kappa) m_.kappa = ternaryMax([&](double k) { return profileWith([k](Model& t) { t.kappa = k; }); }, -1.0, 5.0, 50);
    if (fl_.gamma) m_.gamma = ternaryMax([&](double g) { return profileWith([g](Model& t) { t.gamma = g; }); }, -1.0, 4.0, 50);
    // The dark-surface exponent as the sequence's joint refinement takes it (JointEffects::dark_noise).
    if (fl_.delta) m_.delta = ternaryMax([&](double x) { return profileWith([x](Model& t) { t.delta = x; }); }, -1.0, 3.0, 50);
    profile(m_, &m_.sigma_e);
    if (fl_.drift) fitDrift();
    if (fl_.mixed) fitMixed();
  }
  if (fl_.dof) fitDof();
  if (fl_.quant && m_.q > 0.0) fitCellScale();
  return m_;
}

/// Fits the free parameters of a model on the readings of the training scans (`fits`: the bin
/// locations it ends with).
Model fitModel(const Data& d, const std::vector<bool>& train, const Flags& fl, double q_detected, std::vector<BinFit>& fits) {
  return ModelFitter(d, train, fl, fits).fit(q_detected);
}


// ---------------------------------------------------------------------------------------------
// Statistics (battery) under the baseline.

/// Lag-1 correlation over the scans of each bin (seed 004's independence check), pooled, times
/// sqrt(pairs).
double lag1Correlation(const Data& d, const std::vector<BinFit>& f) {
  double num = 0.0, den = 0.0, n = 0.0;
  for (std::size_t bi = 0; bi < d.bins.size(); ++bi) {
    if (f[bi].n == 0) continue;
    std::vector<std::pair<double, double>> r;
    for (std::size_t i : d.bins[bi].idx) r.push_back({d.t[i], d.y[i] - f[bi].at(d.a[i], d.t[i])});
    std::sort(r.begin(), r.end());
    for (std::size_t k = 1; k < r.size(); ++k)
      if (r[k].first == r[k - 1].first + 1.0) {
        num += r[k].second * r[k - 1].second;
        n += 1.0;
      }
    for (const auto& v : r) den += v.second * v.second;
  }
  return den > 0.0 ? num / den * std::sqrt(std::max(n, 1.0)) : 0.0;
}

std::map<std::string, double> statistics(const Data& d, const std::vector<BinFit>& f, const Model& m, const WallFit& w0,
                                         const WallFit& wb, double q) {
  std::map<std::string, double> st;
  std::vector<double> z, psi, xs, logm, zi, loginc, zc, cb, sb, zd, dark;
  // One recorded value (the RPLIDAR's 47) leaves darkness at rounding level, which the score,
  // scale-free in its covariate, would read as a covariate.
  const bool dark_varies = darknessVaries(d);
  double pos_e = 0, n_e = 0, pos_i = 0, n_i = 0, s_e = 0, s_i = 0;
  double m2 = 0, m4 = 0, nk = 0;
  std::vector<double> y;
  forEachFitted(d, f, [&](std::size_t i, const Bin& b, const BinFit& bf) {
    const double centre = bf.at(d.a[i], d.t[i]);
    const double s = m.sigma_e * shapeOf(m, b, centre);
    const double zz = (d.y[i] - centre) / s;
    y.push_back(d.y[i]);
    z.push_back(zz);
    psi.push_back(huberPsi(zz));
    xs.push_back((d.t[i] - d.t_mean) / s);
    logm.push_back(std::log(std::max(bf.m, 1e-3)));
    cb.push_back(std::cos(b.angle));
    sb.push_back(std::sin(b.angle));
    zc.push_back(zz);
    if (b.inc_known && !b.edge) {
      zi.push_back(zz);
      loginc.push_back(-std::log(b.cos_inc));
    }
    if (dark_varies && !b.edge) {
      zd.push_back(zz);
      dark.push_back(b.dark);
    }
    const double z2 = std::min(zz * zz, 9.0);
    if (b.edge) {
      n_e += 1;
      pos_e += std::abs(zz) > 3.0;
      s_e += z2;
    } else {
      n_i += 1;
      pos_i += std::abs(zz) > 3.0;
      s_i += z2;
      m2 += zz * zz;
      m4 += zz * zz * zz * zz;
      nk += 1;
    }
  });
  st["spread_vs_range"] = spreadScore(z, logm);
  st["spread_vs_incidence"] = spreadScore(zi, loginc);
  st["spread_vs_intensity"] = spreadScore(zd, dark);
  st["residual_vs_time"] = meanScore(psi, xs);
  {
    const double a = spreadScore(zc, cb), b = spreadScore(zc, sb);
    st["spread_vs_bearing"] = cubeRootChi2(a * a + b * b, 2.0);
  }
  st["edge_excess"] = n_e > 0 && n_i > 0 ? (pos_e - n_e * pos_i / n_i) / std::sqrt(n_e) : 0.0;
  st["edge_vs_centre_spread"] = n_e > 0 && n_i > 0 ? s_e / n_e - s_i / n_i : 0.0;
  st["tail_weight"] = nk > 0 ? (m4 / nk) / std::pow(m2 / nk, 2) - 3.0 : 0.0;
  st["quantisation"] = gridResultant(y, q > 0.0 ? q : 1e-3);
  st["lag1_correlation"] = lag1Correlation(d, f);
  st["wall_curvature"] = wb.ok && wb.b_se > 0.0 && std::isfinite(wb.b_se) ? wb.b / wb.b_se : 0.0;
  st["wall_roughness_mm"] = w0.ok ? 1000.0 * w0.tau : 0.0;
  st["range_offset_mm"] = w0.ok ? 1000.0 * w0.alpha0 : 0.0;
  return st;
}

const std::vector<StatisticInfo>& statInfo() {
  static const std::vector<StatisticInfo> info = {
      {"spread_vs_range", "range", "score of the noise growing with ln(mean reading) beyond the squared law, ~N(0,1)", true},
      {"spread_vs_incidence", "incidence angle", "score of the noise growing with -ln cos(incidence), ~N(0,1)", true},
      {"spread_vs_intensity", "intensity", "score of the noise growing with ln(I_median / I), the darkness of the return, away from discontinuities (0 without intensities that vary), ~N(0,1)", true},
      {"spread_vs_bearing", "bearing", "cube root of chi^2 / 2 of the noise against cos and sin of the beam angle", false},
      {"residual_vs_time", "scan index", "score of a trend shared by all beams over the scans, ~N(0,1)", true},
      {"lag1_correlation", "scan index", "pooled lag-1 correlation of successive readings of a beam, times sqrt(pairs)", true},
      {"edge_excess", "position within the object", "|z| > 3 readings at depth discontinuities beyond the rate elsewhere, per sqrt(edge readings)", false},
      {"edge_vs_centre_spread", "position within the object", "mean clipped z^2 at depth discontinuities minus elsewhere", true},
      {"tail_weight", "residual", "excess kurtosis of the standardised residuals (away from discontinuities)", false},
      {"quantisation", "reading", "resultant length of the readings' phase on the detected grid (1: on the grid)", false},
      {"wall_curvature", "incidence angle", "incidence bias b (1 - cos phi) fitted on the wall lines, over its standard error", true},
      {"wall_roughness_mm", "wall", "scatter of the beam means about the wall model, mm", false},
      {"range_offset_mm", "wall", "range offset alpha_0 the walls' straightness implies, mm", true},
  };
  return info;
}

/// Readings on a grid q scored as densities: every model's likelihood is evaluated at the reading
/// plus a uniform draw over its grid cell (uniform dequantisation; Theis, van den Oord & Bethge,
/// "A note on the evaluation of generative models", ICLR 2016). A continuous density evaluated
/// at the grid points themselves is not comparable with the rounded model's cell probability
/// (readingLL): where the noise is finer than the grid it is higher than any probability over
/// q allows. On the dequantised readings both are densities of the same variable, and the
/// rounded model is the true one when the readings were rounded. Fits stay on the readings.
Data dequantise(const Data& d, double q, std::uint64_t seed) {
  Data r = d;
  r.y_cell = d.y;
  auto gen = makeRng(seed, 0x0ULL);
  std::uniform_real_distribution<double> cell(-0.5 * q, 0.5 * q);
  for (double& y : r.y) y += cell(gen);
  return r;
}

/// The baseline's readings, simulated with the project's simulator (reading level): the same
/// beams and scans, true distance from the bin's location (wall bins: the wall model with a
/// roughness draw), the fitted range model, optionally with effects.
Data simulateStatic(const Data& d, const std::vector<BinFit>& f, const WallFit& w, const Model& m, std::uint64_t seed,
                    const RangeEffects& fx) {
  Data r = d;
  RangeModel rm;
  rm.bias.alpha = {w.ok ? w.alpha0 : 0.0, 1.0};
  rm.noise.kind = NoiseKind::power;
  rm.noise.exponent = m.kappa;
  rm.noise.sigma_e = m.sigma_e;
  rm.range_min_m = -1e9;
  rm.range_max_m = 1e9;
  auto rough = makeRng(seed, 0x3A11ULL);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> u(d.bins.size(), 0.0);
  for (double& v : u) v = (w.ok ? w.tau : 0.0) * normal(rough);
  std::map<std::size_t, std::size_t> wall_index;
  for (std::size_t k = 0; k < w.bins.size(); ++k) wall_index[w.bins[k]] = k;
  std::vector<std::mt19937_64> gens;
  std::map<std::uint32_t, std::size_t> gen_of;
  for (std::size_t i = 0; i < d.y.size(); ++i) {
    const int bi = d.bin_of[i];
    if (bi < 0 || f[static_cast<std::size_t>(bi)].n == 0) continue;
    const Bin& b = d.bins[static_cast<std::size_t>(bi)];
    const BinFit& bf = f[static_cast<std::size_t>(bi)];
    double mean = bf.at(d.a[i], d.t[i]);
    if (w.ok && b.wall >= 0 && wall_index.count(static_cast<std::size_t>(bi))) {
      const Line& l = w.lines[static_cast<std::size_t>(b.wall)];
      mean = w.alpha0 + l.p / std::max(std::cos(d.a[i] - l.theta), 0.05) + u[static_cast<std::size_t>(bi)];
    }
    const auto scan = static_cast<std::uint32_t>(d.t[i]);
    auto it = gen_of.find(scan);
    if (it == gen_of.end()) {
      it = gen_of.emplace(scan, gens.size()).first;
      gens.push_back(simulation::effectRng(seed, scan));
    }
    auto& gen = gens[it->second];
    const double e = normal(gen);
    double dist = mean - rm.bias.alpha[0];
    if (fx.mixed_pixel_fraction > 0.0) {
      // At a depth discontinuity the footprint may straddle both surfaces: a reading anywhere
      // between them (the other side is the nearer or the farther one).
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      const double u1 = unit(gen), share = unit(gen);
      if (b.edge && u1 < fx.mixed_pixel_fraction) {
        const double other = (std::abs(mean - b.near) < std::abs(mean - b.far) ? b.far : b.near) - rm.bias.alpha[0];
        dist = share * dist + (1.0 - share) * other;
      }
    }
    RangeEffects no_mix = fx;
    no_mix.mixed_pixel_fraction = 0.0;
    const double intensity = std::isfinite(b.intensity) ? b.intensity : 0.0;
    r.y[i] = simulation::effectReading(rm, no_mix, dist, simulation::BeamContext{b.cos_inc, 0.0, scan, intensity}, e, gen);
  }
  return r;
}

/// Standard error of a normal sample's median over that of its mean: sqrt(pi / 2).
constexpr double kMedianEfficiency = 1.2533141373155003;

/// Whether the sensor moved during the recording: the beams' medians in the first and second
/// half of the scans differ beyond their noise, by different amounts (a drift moves them all alike).
double movedFraction(const Data& d) {
  double tmax = 0.0;
  for (double t : d.t) tmax = std::max(tmax, t);
  std::vector<bool> first(static_cast<std::size_t>(tmax) + 1), second(first.size());
  for (std::size_t t = 0; t < first.size(); ++t) {
    first[t] = static_cast<double>(t) <= tmax / 2.0;
    second[t] = !first[t];
  }
  const auto a = fitBins(d, first, 0.0), b = fitBins(d, second, 0.0);
  std::vector<double> diff, se;
  for (std::size_t k = 0; k < d.bins.size(); ++k) {
    if (a[k].n == 0 || b[k].n == 0) continue;
    // Medians: a person walking past, or a beam flickering onto the vehicle's own body, moves a
    // bin's mean by decimetres while the sensor stands still (the forklift recordings).
    diff.push_back(b[k].med - a[k].med);
    se.push_back(kMedianEfficiency * std::sqrt(a[k].s2 / a[k].n + b[k].s2 / b[k].n));
  }
  if (diff.empty()) return 1.0;
  const double common = upperMedian(diff);
  std::size_t moved = 0;
  std::vector<double> dev;
  for (std::size_t k = 0; k < diff.size(); ++k) {
    moved += std::abs(diff[k] - common) > std::max(5.0 * se[k], 0.01);
    dev.push_back(std::abs(diff[k] - common));
  }
  // Half the beams' means moved by more than 1 cm: the sensor moved, whatever the noise.
  if (upperMedian(dev) > 0.01) return 1.0;
  return static_cast<double>(moved) / static_cast<double>(diff.size());
}

// ---------------------------------------------------------------------------------------------
// The diagnosis of repeated scans: the steps of diagnosis/skeleton.hpp on the bin and wall models.

/// Residual records of a data set under a fit (measured or simulated).
std::vector<ResidualRecord> recordsOf(const Data& dd, const std::vector<BinFit>& ff, const Model& mm) {
  std::vector<ResidualRecord> rec;
  forEachFitted(dd, ff, [&](std::size_t i, const Bin& b, const BinFit& bf) {
    ResidualRecord r;
    r.range_m = bf.m;
    r.incidence_rad = b.inc_known ? std::acos(std::clamp(b.cos_inc, 0.0, 1.0)) : kNaN;
    r.lateral = b.edge ? 1.0 : 0.0;
    r.group = b.wall + 1;
    r.time = dd.t[i];
    r.bearing_rad = b.angle;
    r.edge = b.edge;
    const double centre = bf.at(dd.a[i], dd.t[i]);
    r.residual_m = dd.y[i] - centre;
    r.z = r.residual_m / (mm.sigma_e * shapeOf(mm, b, centre));
    rec.push_back(r);
  });
  return rec;
}

/// Standardised residuals and per-bin variances of simulations refitted with the baseline.
struct SimSample {
  std::vector<double> z;
  std::vector<std::vector<double>> var;  ///< per bin, over the simulations
  void add(const std::vector<ResidualRecord>& rec, const std::vector<BinFit>& fr) {
    for (const auto& r : rec) z.push_back(r.z);
    for (std::size_t k = 0; k < fr.size(); ++k)
      if (fr[k].n > 0) var[k].push_back(fr[k].s2);
  }
};

// ---------------------------------------------------------------------------------------------
// Tails explained (diagnosis/tails.hpp): the contamination model's covariates per bin,
// the residuals it is fitted to, and its variants compared on the same scan folds.

/// The tail model's view of the bins: covariates from the full-data locations `f`.
std::vector<TailBeam> tailBeams(const Data& d, const std::vector<BinFit>& f) {
  double mean_lr = 0.0, n = 0.0;
  for (std::size_t k = 0; k < d.bins.size(); ++k) {
    if (f[k].n == 0) continue;
    mean_lr += std::log(std::max(std::abs(f[k].m), 1e-3));
    n += 1.0;
  }
  mean_lr /= std::max(n, 1.0);
  std::vector<TailBeam> beams(d.bins.size());
  for (std::size_t k = 0; k < d.bins.size(); ++k) {
    const Bin& b = d.bins[k];
    TailBeam& t = beams[k];
    t.log_range = std::log(std::max(std::abs(f[k].m), 1e-3));
    // At a depth edge the tails are the edge's (the bin's mean mixes both surfaces, and the slope
    // it makes with its neighbour may be the jump's): no grazing covariate there. The noise law
    // keeps the incidence (a pillar's silhouette is seen at grazing incidence).
    t.log_sec_inc = b.inc_known ? -std::log(clampCosIncidence(b.cos_inc)) : 0.0;
    t.x[kTailEdge] = b.edge ? 1.0 : 0.0;
    t.x[kTailGrazing] = b.edge ? 0.0 : t.log_sec_inc;
    t.x[kTailRange] = t.log_range - mean_lr;
    // Darkness: how much weaker than the median beam's the return is, ln(I_median / I), >= 0.
    t.x[kTailDark] = std::max(0.0, b.dark);
    t.dark = b.dark;
    if (b.edge && b.far > b.near) {
      t.mix_lo = b.near - f[k].med;
      t.mix_hi = b.far - f[k].med;
    }
  }
  return beams;
}

/// Covariates the data can show: edges at 3 beams or more; the others varying over 3 beams or more.
std::array<bool, kTailCovariates> tailAvailable(const Data& d, const std::vector<TailBeam>& beams, std::size_t edges) {
  std::array<bool, kTailCovariates> a{};
  a[kTailEdge] = edges >= 3;
  for (int j : {kTailGrazing, kTailRange, kTailDark}) {
    std::vector<double> x;
    for (const auto& b : beams) x.push_back(b.x[static_cast<std::size_t>(j)]);
    const double med = x.empty() ? 0.0 : upperMedian(x);
    std::size_t away = 0;
    for (double v : x) away += std::abs(v - med) > 0.1;
    a[static_cast<std::size_t>(j)] = away >= 3;
  }
  a[kTailDark] = a[kTailDark] && d.intensity;
  return a;
}

/// Residuals of the readings about their bin's location (edge bins: about the median, as a
/// mixed-pixel model needs), of the training scans or of the held-out ones; `scans` gets each
/// one's scan. Held out: the location's uncertainty widens the core (factor sqrt(1 + 1/n)).
std::vector<TailReading> tailResiduals(const Data& d, const std::vector<BinFit>& f, const std::vector<bool>& train,
                                       bool held_out, std::vector<std::size_t>* scans) {
  std::vector<TailReading> out;
  forEachFitted(d, f, [&](std::size_t i, const Bin& b, const BinFit& bf) {
    const bool in_train = train.empty() || train[static_cast<std::size_t>(d.t[i])];
    if (in_train == held_out) return;
    TailReading r;
    r.beam = static_cast<std::size_t>(d.bin_of[i]);
    r.residual_m = d.y[i] - bf.at(d.a[i], d.t[i]) - (b.edge ? bf.med - bf.m : 0.0);
    r.inflation = held_out ? std::sqrt(1.0 + 1.0 / std::max(bf.n, 1.0)) : 1.0;
    out.push_back(r);
    if (scans) scans->push_back(static_cast<std::size_t>(d.t[i]));
  });
  return out;
}

/// The tail models compared, their held-out log-likelihoods (aligned with the Gaussian
/// baseline's held-out readings) and the scan of each point.
struct TailStudy {
  std::vector<TailBeam> beams;
  std::array<bool, kTailCovariates> available{};
  std::vector<TailSpec> specs;   ///< 0: pooled, 1: every covariate, then one without each, then robust effects
  std::vector<int> dropped;      ///< covariate left out of spec s (-1: none)
  std::size_t gamma = 0, kappa = 0, mixed = 0, delta = 0;  ///< specs of the robust effects (0: not fitted)
  std::vector<std::vector<double>> ll;
  std::vector<std::size_t> block;
  std::vector<double> gauss;     ///< the Gaussian baseline's held-out log-likelihoods, aligned
  double floor_w = 0.0, floor_density = 0.0;
};

/// The specs: pooled, full, full without each covariate, pooled with each robust effect.
void setupTailSpecs(TailStudy& ts, bool incidence_known, bool edges, bool dark) {
  TailSpec pooled, full;
  full.covariate = ts.available;
  ts.specs = {pooled, full};
  ts.dropped = {-1, -1};
  for (int j = 0; j < kTailCovariates; ++j) {
    if (!ts.available[static_cast<std::size_t>(j)]) continue;
    TailSpec s = full;
    s.covariate[static_cast<std::size_t>(j)] = false;
    ts.specs.push_back(s);
    ts.dropped.push_back(j);
  }
  auto robust = [&](std::size_t& at, auto set) {
    TailSpec s = pooled;
    set(s);
    at = ts.specs.size();
    ts.specs.push_back(s);
    ts.dropped.push_back(-1);
  };
  if (incidence_known) robust(ts.gamma, [](TailSpec& s) { s.gamma = true; });
  robust(ts.kappa, [](TailSpec& s) { s.kappa = true; });
  if (edges) robust(ts.mixed, [](TailSpec& s) { s.mixed = true; });
  if (dark) robust(ts.delta, [](TailSpec& s) { s.delta = true; });
  ts.ll.assign(ts.specs.size(), {});
}

/// Held-out gain of log-likelihoods `a` over `b` (blocks: scans).
HeldOutGain gainOf(const std::vector<double>& a, const std::vector<double>& b, const std::vector<std::size_t>& block) {
  HeldOut h(1);
  h.base = b;  // deliberate copies: a few vectors, once per diagnosis
  h.cand[0] = a;
  h.block = block;
  h.points = static_cast<double>(a.size());
  return heldOutGain(h, 0);
}

/// Class of a beam: the significant covariate whose term raises its tail odds most (at least
/// twofold), else unknown.
std::string tailClass(const TailModel& m, const TailBeam& b, const std::vector<TailCovariateResult>& covs) {
  std::string cls = "unknown";
  double best = std::log(2.0);
  for (const auto& c : covs) {
    if (!c.significant) continue;
    int j = 0;
    while (c.covariate != tailCovariateName(j)) ++j;
    const double term = m.beta[static_cast<std::size_t>(1 + j)] * b.x[static_cast<std::size_t>(j)];
    if (term > best) {
      best = term;
      cls = c.covariate;
    }
  }
  return cls;
}

/// Repeated scans from one pose, diagnosed with the bin and wall models (the problem object of
/// runDiagnosis; its steps in the order they run).
class StaticDiagnosis {
 public:
  StaticDiagnosis(const StaticScans& data, const DiagnoseConfig& config, const std::vector<Effect>& candidates,
                  std::vector<WallLine>* walls_out)
      : data_(data), config_(config), candidates_(candidates), walls_out_(walls_out) {}
  StaticDiagnosis(const StaticDiagnosis&) = delete;  // scored_ points into the object
  StaticDiagnosis& operator=(const StaticDiagnosis&) = delete;

  bool fitBaseline(DiagnosisResult& out);
  std::map<std::string, double> measuredStatistics(DiagnosisResult& out);
  void replica(int b, std::map<std::string, std::vector<double>>& stats, DiagnosisResult& out);
  const std::vector<StatisticInfo>& statisticInfo() const { return statInfo(); }
  void heldOut(HeldOut& held);
  const char* noHeldOut() const { return "no held-out reading"; }
  void beforeCandidates(DiagnosisResult& out);
  CandidateResult candidate(std::size_t c, const HeldOut& held, const DiagnosisResult& out);
  void afterCandidates(DiagnosisResult& out);
  std::vector<std::pair<Effect, Effect>> nestedEffects() const { return {}; }
  void refineCause(DiagnosisResult& out);
  void refineCauseByTails(DiagnosisResult& out);
  /// A pooled contamination above this share is the main component, not a tail.
  static constexpr double kMostReadings = 0.5;
  double darkRangeCorrelation() const;
  /// Covariates this correlated cannot be told apart.
  static constexpr double kConfounded = 0.95;
  bool reRankUnderTails(DiagnosisResult& out);
  Closeness closenessBaseline(const DiagnosisResult& out) const { return closenessOf(out.measured, sim_base_); }
  void extend(std::size_t c, DiagnosisResult& out) const;

 private:
  bool makeData(DiagnosisResult& out);
  void fitWallModel();
  void describeBaseline(DiagnosisResult& out) const;
  std::vector<std::pair<double, double>> lineExtents() const;
  double wallSector() const;
  void reportWalls() const;
  void foldLikelihoods(int k, const std::vector<int>& fold, HeldOut& held) const;
  void wallLikelihoods(HeldOut& held) const;
  void startTails();
  void tailFold(int k, const std::vector<int>& fold);
  void tailCovariateGains(TailAttribution& ta) const;
  TailModel tailFullData(TailAttribution& ta, const std::vector<TailReading>& all) const;
  void tailClasses(TailAttribution& ta, const TailModel& full, const std::vector<TailReading>& all) const;
  void tailRobust(DiagnosisResult& out, const std::vector<TailReading>& all, const TailModel& pooled);
  double inSample(const Flags& fl, Model* fitted) const;
  bool notApplicable(CandidateResult& r) const;
  void setIdentifiability(CandidateResult& r) const;
  void setEstimates(CandidateResult& r, const Model& fm) const;
  void setSceneKeys(DiagnosisResult& out, double a0, const Model& sim_model, const RangeEffects& fx) const;
  Closeness closenessOf(const std::vector<ResidualRecord>& measured, const SimSample& sim) const;

  const StaticScans& data_;
  const DiagnoseConfig& config_;
  const std::vector<Effect>& candidates_;
  std::vector<WallLine>* walls_out_;
  std::size_t window_ = 0;        // scans per window (0: one pose)
  Data d_;                        // readings in direction bins
  std::vector<BinFit> f0_;        // the baseline's bin locations
  Model base0_;                   // the baseline's reading model
  std::vector<Line> lines0_;      // wall lines found in the bin means
  double given_a0_ = kNaN;        // alpha_0 held (NaN: from the walls' straightness)
  bool a0_identified_ = false;
  WallFit w0_, wb_;               // the wall model without and with the incidence bias
  double q_ = 0.0;                // reading grid (0: none)
  Data dequantised_;              // d_ with every reading spread over its grid cell (q_ > 0)
  const Data* scored_ = &d_;      // the readings every likelihood is scored on (d_ or dequantised_)
  std::size_t edges_ = 0;         // bins at depth discontinuities
  SimSample sim_base_;            // baseline replicas (closeness)
  std::vector<Flags> flags_;      // per candidate
  double ll_in_base_ = 0.0;       // in-sample log-likelihood of the baseline
  std::vector<Model> full_;       // per candidate: fitted on all the data
  bool tails_on_ = false;         // the tail study runs (heavy_tails is a candidate)
  TailStudy tails_;               // the tail models and their held-out log-likelihoods
  std::map<Effect, double> robust_;  // effect -> its parameter fitted under the pooled contamination
  std::map<Effect, double> robust_sigma_;  // effect -> the core's sigma_e fitted with it
  bool named_by_tails_ = false;   // the cause was named from the tails' covariates
};

bool StaticDiagnosis::fitBaseline(DiagnosisResult& out) {
  if (!makeData(out)) return false;
  // 1. Baseline: bin locations, the squared noise law, the wall model with alpha_0.
  fitWallModel();
  if (std::isfinite(config_.static_range_offset_m)) out.baseline_extra["alpha0_given_m"] = given_a0_;
  std::vector<double> used_y;
  for (std::size_t i = 0; i < d_.y.size(); ++i)
    if (d_.bin_of[i] >= 0) used_y.push_back(d_.y[i]);
  q_ = detectReadingGrid(used_y);
  if (q_ > 0.0) {
    dequantised_ = dequantise(d_, q_, deriveSeed(config_.seed, 0xDE0A7ULL));
    scored_ = &dequantised_;
  }
  for (const auto& b : d_.bins) edges_ += b.edge;
  describeBaseline(out);
  if (walls_out_) reportWalls();
  // The noise is read against range and incidence off the walls: straight surfaces seen over a
  // narrow sector (one target, such as the retro-reflector a range sweep was masked to) hold
  // neither spread, and any effect named from them would be chance.
  if (const double span = wallSector(); span < kMinWallSectorRad) {
    out.status.code = StatusCode::too_few_walls;
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "the returns lie on %s seen over %.1f degrees (at least %.0f needed): record the "
                  "repeated scans in a room with walls in view at several distances, not one target alone",
                  plural(lines0_.size(), "straight surface").c_str(), rad2deg(span), rad2deg(kMinWallSectorRad));
    out.status.message = buf;
    return false;
  }
  return true;
}

/// The first and last beam angle of each wall line, over the bins the wall model fits
/// (+inf, -inf for a line without any).
std::vector<std::pair<double, double>> StaticDiagnosis::lineExtents() const {
  std::vector<std::pair<double, double>> ext(lines0_.size(), {kInf, -kInf});
  for (std::size_t bi : w0_.bins) {
    const Bin& b = d_.bins[bi];
    auto& [lo, hi] = ext.at(static_cast<std::size_t>(b.wall));
    lo = std::min(lo, b.angle);
    hi = std::max(hi, b.angle);
  }
  return ext;
}

/// The beam sector the wall lines cover: the sum over lines of the angles between their first and
/// last bin.
double StaticDiagnosis::wallSector() const {
  double sum = 0.0;
  for (const auto& [lo, hi] : lineExtents())
    if (hi >= lo) sum += hi - lo;
  return sum;
}

/// One pose for the whole recording, unless the beams show that the sensor moved: then short
/// windows of scans, each a pose of its own, with a time trend per beam (the sensor creeping).
bool StaticDiagnosis::makeData(DiagnosisResult& out) {
  if (data_.scans < static_cast<std::size_t>(2 * config_.folds)) {
    out.status.code = StatusCode::too_few_scans;
    out.status.message = "a static recording needs at least " + std::to_string(2 * config_.folds) + " scans from the same pose";
    return false;
  }
  window_ = config_.static_window > 0 ? static_cast<std::size_t>(config_.static_window) : 0;
  d_ = makeBins(data_, window_);
  if (config_.static_window == 0) {
    const double moved = movedFraction(d_);
    out.baseline_extra["beams_moved_fraction"] = moved;
    if (moved > 0.3) {
      window_ = 8;
      d_ = makeBins(data_, window_);
    }
  }
  out.baseline_extra["window_scans"] = static_cast<double>(window_);
  // One pose: beams that saw objects move (a person, a reflector carried away) are left out;
  // the sensor's model is about the scene standing still.
  if (window_ == 0) out.baseline_extra["scene_changed_bins"] = static_cast<double>(dropChangedBins(d_));
  if (d_.bins.size() < 10) {
    out.status.code = StatusCode::too_few_beams;
    out.status.message = "fewer than 10 beam directions return in enough scans";
    return false;
  }
  return true;
}

void StaticDiagnosis::fitWallModel() {
  base0_ = fitModel(d_, {}, Flags{}, 0.0, f0_);
  lines0_ = findWalls(d_, f0_);
  given_a0_ = config_.static_range_offset_m;  // NaN: from the walls' straightness
  w0_ = fitWalls(d_, f0_, lines0_, false, given_a0_);
  // Walls too few or too short to bend measurably: alpha_0 stays unknown (held at 0).
  a0_identified_ = std::isfinite(given_a0_) || (w0_.ok && w0_.alpha0_se <= 0.05);
  if (!a0_identified_) {
    given_a0_ = 0.0;
    w0_ = fitWalls(d_, f0_, lines0_, false, given_a0_);
  }
  wb_ = fitWalls(d_, f0_, lines0_, true, given_a0_);
}

void StaticDiagnosis::describeBaseline(DiagnosisResult& out) const {
  out.landmarks = lines0_.size();
  out.baseline.bias.alpha = {w0_.ok ? w0_.alpha0 : 0.0, 1.0};
  out.baseline.noise.kind = NoiseKind::squared;
  out.baseline.noise.sigma_e = base0_.sigma_e;
  out.baseline.range_min_m = data_.range_min_m;
  out.baseline.range_max_m = data_.range_max_m;
  auto& extra = out.baseline_extra;
  extra["beam_bins"] = static_cast<double>(d_.bins.size());
  extra["wall_lines"] = static_cast<double>(lines0_.size());
  extra["wall_bins"] = static_cast<double>(w0_.bins.size());
  extra["alpha0_m"] = w0_.ok && a0_identified_ ? w0_.alpha0 : kNaN;
  extra["alpha0_se_m"] = w0_.ok && a0_identified_ && !std::isfinite(config_.static_range_offset_m) ? w0_.alpha0_se : kNaN;
  extra["wall_roughness_m"] = w0_.ok ? w0_.tau : kNaN;
  extra["reading_grid_m"] = q_;
  extra["edge_bins"] = static_cast<double>(edges_);
}

/// The fitted wall lines, for the caller (the geometric reference).
void StaticDiagnosis::reportWalls() const {
  walls_out_->clear();
  const auto extents = lineExtents();
  for (std::size_t l = 0; l < lines0_.size(); ++l) {
    WallLine wl;
    const Line& line = w0_.ok ? w0_.lines[l] : lines0_[l];
    wl.normal_rad = wrapAngle(line.theta);
    wl.distance_m = line.p;
    // Residuals exist only when the wall model's fit ran to its end (fitWalls returns early on
    // too few bins or a failed step).
    const bool fitted = w0_.resid.size() == w0_.bins.size();
    double ss = 0.0;
    for (std::size_t k = 0; k < w0_.bins.size(); ++k) {
      if (d_.bins[w0_.bins[k]].wall != static_cast<int>(l)) continue;
      ++wl.bins;
      if (fitted) ss += w0_.resid[k] * w0_.resid[k];
    }
    wl.first_angle_rad = extents[l].first;
    wl.last_angle_rad = extents[l].second;
    wl.rms_m = !wl.bins ? 0.0 : fitted ? std::sqrt(ss / static_cast<double>(wl.bins)) : kNaN;
    walls_out_->push_back(wl);
  }
}

std::map<std::string, double> StaticDiagnosis::measuredStatistics(DiagnosisResult& out) {
  const auto measured_stats = statistics(d_, f0_, base0_, w0_, wb_, q_);
  out.measured = recordsOf(d_, f0_, base0_);
  sim_base_.var.resize(d_.bins.size());
  return measured_stats;
}

/// One bootstrap replica: simulated from the fitted baseline, refitted from it.
void StaticDiagnosis::replica(int b, std::map<std::string, std::vector<double>>& stats, DiagnosisResult& out) {
  const Data rep = simulateStatic(d_, f0_, w0_, base0_, deriveSeed(config_.seed, 2000 + static_cast<std::uint64_t>(b)), RangeEffects{});
  std::vector<BinFit> fr;
  const Model mr = fitModel(rep, {}, Flags{}, 0.0, fr);
  const WallFit wr0 = fitWalls(rep, fr, w0_.ok ? w0_.lines : lines0_, false, given_a0_);
  const WallFit wrb = fitWalls(rep, fr, w0_.ok ? w0_.lines : lines0_, true, given_a0_);
  for (const auto& [k, v] : statistics(rep, fr, mr, wr0, wrb, q_)) stats[k].push_back(v);
  if (b >= config_.closeness_replicas && b != 0) return;
  const auto rec = recordsOf(rep, fr, mr);
  if (b < config_.closeness_replicas) sim_base_.add(rec, fr);
  if (b == 0) out.simulated_baseline = rec;
}

/// Held-out readings (folds by scan) and held-out wall bins (leave one out).
void StaticDiagnosis::heldOut(HeldOut& held) {
  std::vector<int> fold(data_.scans);
  for (std::size_t t = 0; t < data_.scans; ++t) fold[t] = static_cast<int>(t % static_cast<std::size_t>(config_.folds));
  for (const auto& e : candidates_) flags_.push_back(flagsOf(e));
  startTails();
  const auto folds = static_cast<std::size_t>(config_.folds);
  for (int k = 0; k < config_.folds; ++k) {
    reportProgress(config_, kHeldOutStage, static_cast<std::size_t>(k), folds);
    foldLikelihoods(k, fold, held);
    if (tails_on_) tailFold(k, fold);
  }
  reportProgress(config_, kHeldOutStage, folds, folds);
  held.points = static_cast<double>(held.base.size());
  if (tails_on_) tails_.gauss = held.base;  // the readings' part (the wall bins come next); deliberate copy
  wallLikelihoods(held);
}

/// Readings of fold k's scans under the models fitted on the other scans (block: scan).
void StaticDiagnosis::foldLikelihoods(int k, const std::vector<int>& fold, HeldOut& held) const {
  const double floor_w = config_.outlier_floor;
  std::vector<bool> train(data_.scans);
  for (std::size_t t = 0; t < data_.scans; ++t) train[t] = fold[t] != k;
  std::vector<BinFit> fb;
  const Model mb = fitModel(d_, train, Flags{}, q_, fb);
  std::vector<std::vector<BinFit>> fc(candidates_.size());
  std::vector<Model> mc(candidates_.size());
  for (std::size_t c = 0; c < candidates_.size(); ++c) mc[c] = fitModel(d_, train, flags_[c], q_, fc[c]);
  for (std::size_t i = 0; i < d_.y.size(); ++i) {
    const int bi = d_.bin_of[i];
    if (bi < 0 || train[static_cast<std::size_t>(d_.t[i])] || fb[static_cast<std::size_t>(bi)].n == 0) continue;
    const Bin& bin = d_.bins[static_cast<std::size_t>(bi)];
    held.base.push_back(readingLL(mb, *scored_, bin, fb[static_cast<std::size_t>(bi)], i, floor_w));
    held.block.push_back(static_cast<std::size_t>(d_.t[i]));
    for (std::size_t c = 0; c < candidates_.size(); ++c)
      held.cand[c].push_back(fc[c][static_cast<std::size_t>(bi)].n > 0
                                 ? readingLL(mc[c], *scored_, bin, fc[c][static_cast<std::size_t>(bi)], i, floor_w)
                                 : kNaN);
  }
}

/// The tail study's beams, covariates and specs (only when heavy_tails is a candidate).
void StaticDiagnosis::startTails() {
  tails_on_ = std::find(candidates_.begin(), candidates_.end(), Effect::heavy_tails) != candidates_.end();
  if (!tails_on_) return;
  tails_.beams = tailBeams(d_, f0_);
  tails_.available = tailAvailable(d_, tails_.beams, edges_);
  std::size_t inc_known = 0;
  for (const auto& b : d_.bins) inc_known += b.inc_known;
  setupTailSpecs(tails_, inc_known >= 3, edges_ >= 3, darknessVaries(d_));
  tails_.floor_w = config_.outlier_floor;
  tails_.floor_density = d_.window_max > d_.window_min ? 1.0 / (d_.window_max - d_.window_min) : 0.0;
}

/// Fold k's readings under every tail model fitted on the other scans (the same folds, the same
/// held-out readings in the same order as the Gaussian baseline's).
void StaticDiagnosis::tailFold(int k, const std::vector<int>& fold) {
  std::vector<bool> train(data_.scans);
  for (std::size_t t = 0; t < data_.scans; ++t) train[t] = fold[t] != k;
  const std::vector<BinFit> fits = fitBins(d_, train, 0.0);
  const auto fit_on = tailResiduals(d_, fits, train, false, nullptr);
  const auto test = tailResiduals(*scored_, fits, train, true, &tails_.block);
  // Warm starts: the full model from the pooled one, each model without a covariate from the
  // full one, the robust effects from the pooled one.
  std::vector<TailModel> models;
  for (std::size_t s = 0; s < tails_.specs.size(); ++s) {
    const TailModel* warm = s == 0 ? nullptr : tails_.dropped[s] >= 0 ? &models[1] : &models[0];
    models.push_back(
        fitTailModel(tails_.beams, fit_on, tails_.specs[s], base0_.sigma_e, tails_.floor_w, tails_.floor_density, 60, warm));
    for (const auto& r : test)
      tails_.ll[s].push_back(
          models[s].logDensity(tails_.beams[r.beam], r.residual_m, r.inflation, tails_.floor_w, tails_.floor_density));
  }
}

/// Step 3 for the tails: held-out gains (pooled over the Gaussian baseline, covariates over the
/// pooled model, each covariate's unique part), the full model on all the data, the robust effects.
void StaticDiagnosis::afterCandidates(DiagnosisResult& out) {
  TailAttribution& ta = out.tails;
  if (!tails_on_) {
    ta.note = "heavy_tails is not among the candidates";
    return;
  }
  if (tails_.gauss.empty() || tails_.ll[0].size() != tails_.gauss.size()) {
    ta.note = "no held-out reading for the tail models";
    return;
  }
  ta.fitted = true;
  const HeldOutGain pooled = gainOf(tails_.ll[0], tails_.gauss, tails_.block);
  const HeldOutGain explained = gainOf(tails_.ll[1], tails_.ll[0], tails_.block);
  ta.pooled_gain_nats_per_point = pooled.gain;
  ta.pooled_gain_se = pooled.se;
  ta.explained_gain_nats_per_point = explained.gain;
  ta.explained_gain_se = explained.se;
  const HeldOutGain total = gainOf(tails_.ll[1], tails_.gauss, tails_.block);
  ta.p_value = total.finite ? heldoutPValue(total.gain, total.se) : 1.0;
  tailCovariateGains(ta);
  const auto all = tailResiduals(d_, f0_, {}, false, nullptr);
  const TailModel pooled_all = tailFullData(ta, all);
  tailRobust(out, all, pooled_all);
}

/// Each covariate's unique held-out gain (the full model over the model without it), Holm across
/// them; the cause is the effect of the one with the largest significant gain.
void StaticDiagnosis::tailCovariateGains(TailAttribution& ta) const {
  std::vector<double> p;
  for (std::size_t s = 0; s < tails_.specs.size(); ++s) {
    const int j = tails_.dropped[s];
    if (j < 0) continue;
    TailCovariateResult c;
    c.covariate = tailCovariateName(j);
    c.effect = tailCovariateEffect(j);
    const HeldOutGain g = gainOf(tails_.ll[1], tails_.ll[s], tails_.block);
    c.unique_gain_nats_per_point = g.gain;
    c.unique_gain_se = g.se;
    c.p_value = g.finite ? heldoutPValue(g.gain, g.se) : kNaN;
    c.share = ta.explained_gain_nats_per_point > 0.0 ? g.gain / ta.explained_gain_nats_per_point : 0.0;
    p.push_back(c.p_value);
    ta.covariates.push_back(c);
  }
  const auto adj = holmAdjust(p);
  const TailCovariateResult* top = nullptr;
  for (std::size_t k = 0; k < ta.covariates.size(); ++k) {
    TailCovariateResult& c = ta.covariates[k];
    c.p_holm = adj[k];
    c.significant = std::isfinite(adj[k]) && adj[k] < config_.alpha && c.unique_gain_nats_per_point > 0.0;
    if (c.significant && (!top || c.unique_gain_nats_per_point > top->unique_gain_nats_per_point)) top = &c;
  }
  ta.cause = top ? toString(top->effect) : cause::kUnknown;
}

/// The pooled and the full tail models on all the data: parameters, and which beams carry the
/// tails. Returns the pooled model (the robust effects start from it).
TailModel StaticDiagnosis::tailFullData(TailAttribution& ta, const std::vector<TailReading>& all) const {
  const double fw = tails_.floor_w, fd = tails_.floor_density;
  const TailModel pooled = fitTailModel(tails_.beams, all, tails_.specs[0], base0_.sigma_e, fw, fd);
  ta.pooled_fraction = pooled.tailProbability(TailBeam{});
  ta.pooled_wide_scale = pooled.wide;
  const TailModel full = fitTailModel(tails_.beams, all, tails_.specs[1], base0_.sigma_e, fw, fd, 60, &pooled);
  ta.model["sigma_e"] = full.sigma_e;
  ta.model["wide_scale"] = full.wide;
  ta.model["wide_range_exponent"] = full.wide_exponent;
  ta.model["reference_range_m"] = std::exp(full.ref_log_range);
  ta.model["logit_intercept"] = full.beta[0];
  ta.model["em_iterations"] = full.iterations;
  ta.model["em_converged"] = full.converged ? 1.0 : 0.0;
  for (auto& c : ta.covariates) {
    int j = 0;
    while (c.covariate != tailCovariateName(j)) ++j;
    c.coefficient = full.beta[static_cast<std::size_t>(1 + j)];
    ta.model["logit_" + c.covariate] = c.coefficient;
  }
  tailClasses(ta, full, all);
  return pooled;
}

/// Tail readings (posterior sums) by class of beam, and the beams with the largest tail fraction.
void StaticDiagnosis::tailClasses(TailAttribution& ta, const TailModel& full, const std::vector<TailReading>& all) const {
  std::vector<double> tail(d_.bins.size(), 0.0), n(d_.bins.size(), 0.0);
  for (const auto& r : all) {
    tail[r.beam] += full.responsibility(tails_.beams[r.beam], r.residual_m, r.inflation, tails_.floor_w, tails_.floor_density);
    n[r.beam] += 1.0;
  }
  for (const char* cls : {"edge", "grazing", "range", "dark", "unknown"}) {
    ta.tail_readings_by_class[cls] = 0.0;
    ta.readings_by_class[cls] = 0.0;
  }
  std::vector<TailBeamReport> beams;
  for (std::size_t b = 0; b < d_.bins.size(); ++b) {
    if (n[b] == 0.0) continue;
    const std::string cls = tailClass(full, tails_.beams[b], ta.covariates);
    ta.tail_readings += tail[b];
    ta.tail_readings_by_class[cls] += tail[b];
    ta.readings_by_class[cls] += n[b];
    TailBeamReport r;
    const Bin& bin = d_.bins[b];
    r.bearing_rad = bin.angle;
    r.range_m = f0_[b].m;
    r.incidence_rad = bin.inc_known ? std::acos(std::clamp(bin.cos_inc, 0.0, 1.0)) : kNaN;
    r.intensity = bin.intensity;
    r.edge = bin.edge;
    r.readings = static_cast<std::size_t>(n[b]);
    r.tail_fraction = tail[b] / n[b];
    r.tail_probability = full.tailProbability(tails_.beams[b]);
    r.cls = cls;
    beams.push_back(r);
  }
  std::stable_sort(beams.begin(), beams.end(), [](const TailBeamReport& a, const TailBeamReport& b) { return a.tail_fraction > b.tail_fraction; });
  if (beams.size() > 10) beams.resize(10);
  ta.top_beams = std::move(beams);
}

/// Incidence exponent, range exponent, mixed-pixel fraction and dark-surface exponent fitted under
/// the pooled contamination (the tails do not drag them), with their held-out gains over the pooled model.
void StaticDiagnosis::tailRobust(DiagnosisResult& out, const std::vector<TailReading>& all, const TailModel& pooled) {
  struct Item {
    std::size_t spec;
    Effect effect;
    const char* key;
  };
  const Item items[] = {{tails_.gamma, Effect::incidence_noise, "incidence_noise_exponent"},
                        {tails_.kappa, Effect::range_noise_law, "noise_exponent"},
                        {tails_.mixed, Effect::mixed_pixels, "mixed_pixel_fraction"},
                        {tails_.delta, Effect::dark_surface, "dark_noise_exponent"}};
  for (const Item& it : items) {
    if (it.spec == 0) continue;
    const TailModel m =
        fitTailModel(tails_.beams, all, tails_.specs[it.spec], base0_.sigma_e, tails_.floor_w, tails_.floor_density, 60, &pooled);
    const double value = it.spec == tails_.gamma   ? m.gamma
                         : it.spec == tails_.kappa ? m.kappa
                         : it.spec == tails_.delta ? m.delta
                                                   : m.mixed;
    const HeldOutGain g = gainOf(tails_.ll[it.spec], tails_.ll[0], tails_.block);
    const std::string key = it.key;
    out.tails.robust[key] = value;
    out.tails.robust[key + "_gain"] = g.gain;
    out.tails.robust[key + "_gain_se"] = g.se;
    out.tails.robust[key + "_p"] = g.finite ? heldoutPValue(g.gain, g.se) : 1.0;
    robust_[it.effect] = value;
    robust_sigma_[it.effect] = m.sigma_e;
    for (auto& c : out.candidates)
      if (c.effect == it.effect) c.estimates[key + "_robust"] = value;
  }
}

/// The effects fitted under the pooled contamination (StaticDiagnosis::tailRobust): their key in
/// TailAttribution::robust, or nullptr.
const char* robustEffectOf(Effect e) {
  if (e == Effect::incidence_noise) return "incidence_noise_exponent";
  if (e == Effect::range_noise_law) return "noise_exponent";
  if (e == Effect::mixed_pixels) return "mixed_pixel_fraction";
  if (e == Effect::dark_surface) return "dark_noise_exponent";
  return nullptr;
}

/// A noise law, mixed pixels or a dark surface named while the tails are significant: the Gaussian
/// likelihood the ranking came from is dominated by the tails, so the four are ranked again by
/// their held-out gains over the pooled contamination (Holm across them); the largest significant
/// one is named. False when none is significant there (the verdict is left to the caller).
bool StaticDiagnosis::reRankUnderTails(DiagnosisResult& out) {
  named_by_tails_ = true;  // its simulation takes the exponent fitted beside the contamination
  const auto& rob = out.tails.robust;
  std::vector<Effect> effects;
  std::vector<double> p;
  for (Effect e : {Effect::incidence_noise, Effect::range_noise_law, Effect::mixed_pixels, Effect::dark_surface}) {
    const std::string key = robustEffectOf(e);
    if (!rob.count(key + "_p")) continue;
    effects.push_back(e);
    p.push_back(rob.at(key + "_p"));
  }
  const auto adj = holmAdjust(p);
  std::string best;
  double best_gain = 0.0;
  for (std::size_t k = 0; k < effects.size(); ++k) {
    const double gain = rob.at(std::string(robustEffectOf(effects[k])) + "_gain");
    if (adj[k] < config_.alpha && gain > best_gain) {
      best_gain = gain;
      best = toString(effects[k]);
    }
  }
  if (best.empty()) return false;
  if (best == out.primary_cause) return true;
  out.decision = "the tails are significant and dominate the Gaussian likelihood that ranked " + out.primary_cause +
                 " first; fitted beside a pooled contamination, " + best + " has the largest significant held-out gain (+" +
                 std::to_string(best_gain) + " nats per reading)";
  out.primary_cause = best;
  return true;
}

/// Step 4 for the tails (refineCauseByTails), with a caution when the contamination the cause was
/// named beside holds most of the readings: it is then the main component, not a tail, and what is
/// fitted beside it describes the wild readings more than the sensor (the forklift's back lidars,
/// which see the vehicle's own body, docs/FINDINGS.md).
void StaticDiagnosis::refineCause(DiagnosisResult& out) {
  refineCauseByTails(out);
  if (named_by_tails_ && out.tails.pooled_fraction > kMostReadings)
    out.decision += "; caution: the pooled contamination holds " +
                    std::to_string(static_cast<int>(std::lround(100.0 * out.tails.pooled_fraction))) +
                    " % of the readings, so the values fitted beside it describe those readings more than the sensor's "
                    "core noise: look for what the beams see besides the scene (the vehicle's body, moving objects) and "
                    "leave it out (import --range-min, a shorter stretch of scans)";
}

/// When the named cause is the pooled symptom (heavy_tails) or nothing while the tails are
/// significant, the physical effect whose covariate carries the largest significant share of the
/// tails' explained log-likelihood; heavy_tails, cause unknown, when none does. A noise law, mixed
/// pixels or a dark surface named from the Gaussian ranking: ranked again beside the contamination.
void StaticDiagnosis::refineCauseByTails(DiagnosisResult& out) {
  TailAttribution& ta = out.tails;
  if (!ta.fitted) return;
  double tested = 1.0;
  bool heavy = false;
  for (const auto& c : out.candidates) {
    tested += std::isfinite(c.p_value) && c.applicable;
    heavy = heavy || (c.effect == Effect::heavy_tails && c.significant);
  }
  ta.significant = heavy || std::min(1.0, tested * ta.p_value) < config_.alpha;
  if (!ta.significant) return;
  const std::optional<Effect> named = parseEffect(out.primary_cause);
  std::string why;  // why the tails' cause replaces the Gaussian ranking's
  if (named && robustEffectOf(*named)) {
    if (reRankUnderTails(out)) return;
    // None of the four is significant beside the contamination: the tails made the Gaussian
    // verdict, and the tails' own cause is named (seeds 402 and 406 of the edge tails).
    named_by_tails_ = false;
    why = out.primary_cause +
          ", first under the Gaussian likelihood, is not significant beside a pooled contamination (nor is another noise "
          "law, mixed pixels or a dark surface)";
    out.primary_cause = cause::kNone;
  }
  if (!names(out.primary_cause, Effect::heavy_tails) && out.primary_cause != cause::kNone) return;
  if (ta.cause == cause::kUnknown) {
    if (!why.empty()) out.decision = why;
    else if (out.primary_cause == cause::kNone)
      out.decision = "the tails are significant (a contamination mixture predicts held-out readings better, p " +
                     std::to_string(ta.p_value) + ") but no candidate is";
    out.primary_cause = toString(Effect::heavy_tails);
    out.decision += "; no covariate of the tails (edge, grazing, range, dark) explains them held out: cause unknown";
    return;
  }
  const TailCovariateResult* top = nullptr;
  for (const auto& c : ta.covariates)
    if (c.significant && names(ta.cause, c.effect) && (!top || c.unique_gain_nats_per_point > top->unique_gain_nats_per_point)) top = &c;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "the tails are significant; of what their covariates explain "
                "held out (+%.4g nats per reading over a pooled contamination), `%s` carries the largest significant share "
                "(%.0f %%, +%.4g +- %.2g nats, Holm p %.2g): %s",
                ta.explained_gain_nats_per_point, top->covariate.c_str(), 100.0 * top->share, top->unique_gain_nats_per_point,
                top->unique_gain_se, top->p_holm, ta.cause.c_str());
  out.decision = why.empty() ? std::string(buf) : why + "; " + buf;
  out.primary_cause = ta.cause;
  named_by_tails_ = true;
  // The tail model until the named effect's candidate replaces it (every cause the tails name is a
  // candidate; dark_surface's model is the Gaussian noise law with the
  // darkness factor, simulated with the exponent fitted on all readings).
  out.extended_parameters = ta.model;
  out.gain_heldout_nats_per_point = ta.pooled_gain_nats_per_point + ta.explained_gain_nats_per_point;
}

/// Wall bins: the bin means given the wall model (baseline: alpha_0 and lines).
void StaticDiagnosis::wallLikelihoods(HeldOut& held) const {
  if (!w0_.ok) return;
  for (std::size_t k = 0; k < w0_.loo_ll.size(); ++k) {
    held.base.push_back(w0_.loo_ll[k]);
    held.block.push_back(std::numeric_limits<std::size_t>::max() - k);
    for (std::size_t c = 0; c < candidates_.size(); ++c)
      held.cand[c].push_back(flags_[c].wall_b && wb_.ok ? wb_.loo_ll[k] : w0_.loo_ll[k]);
  }
}

/// In-sample log-likelihood of a model fitted on all the data (for delta AIC).
double StaticDiagnosis::inSample(const Flags& fl, Model* fitted) const {
  std::vector<BinFit> ff;
  const Model mm = fitModel(d_, {}, fl, q_, ff);
  if (fitted) *fitted = mm;
  double s = 0.0;
  forEachFitted(d_, ff, [&](std::size_t i, const Bin& b, const BinFit& bf) { s += readingLL(mm, *scored_, b, bf, i, config_.outlier_floor); });
  return s;
}

void StaticDiagnosis::beforeCandidates(DiagnosisResult& out) {
  ll_in_base_ = inSample(Flags{}, nullptr);
  out.baseline_neg_log_likelihood = -ll_in_base_;
  full_.resize(candidates_.size());
}

CandidateResult StaticDiagnosis::candidate(std::size_t c, const HeldOut& held, const DiagnosisResult& out) {
  CandidateResult r;
  r.effect = candidates_[c];
  r.statistic = statisticOf(r.effect, DiagnoseMode::static_scene);
  if (notApplicable(r)) return r;
  setScore(r, out.battery);
  const HeldOutGain gain = heldOutGain(held, c);
  if (!gain.finite) {
    r.applicable = false;
    r.p_value = kNaN;
    r.note = "could not be fitted on every fold";
    return r;
  }
  setHeldOutGain(r, gain);
  // A reading grid is plain in the readings (the `quantisation` statistic), on real sensors as
  // much as in simulations; whether the rounding explains anything is the held-out gain's to say
  // (on the dequantised readings, where the rounded model is the true one when it is).
  r.p_value = r.effect == Effect::quantisation ? r.p_heldout : combinedPValue(r.p_heldout, r.score_p_value);
  r.parameters = flags_[c].parameters();
  double ll_in = inSample(flags_[c], &full_[c]);
  if (flags_[c].wall_b && wb_.ok && w0_.ok) ll_in = ll_in_base_ + (wb_.in_ll - w0_.in_ll);  // only the walls' part differs
  r.delta_aic = 2.0 * r.parameters - 2.0 * (ll_in - ll_in_base_);
  setIdentifiability(r);
  setEstimates(r, full_[c]);
  return r;
}

/// Effects one pose cannot show, or that each wall line absorbs: no test.
bool StaticDiagnosis::notApplicable(CandidateResult& r) const {
  const Effect e = r.effect;
  if (e == Effect::heading_error || e == Effect::angle_offset || e == Effect::odometry_scale) {
    r.applicable = false;
    r.identifiable = false;
    r.p_value = r.p_holm = r.score_p_value = kNaN;
    r.note = "one pose: nothing about stops or headings can be seen";
    return true;
  }
  if (e == Effect::dark_surface && !darknessVaries(d_)) {
    r.applicable = false;
    r.p_value = r.p_holm = r.score_p_value = kNaN;
    r.note = "no reading records a return intensity (or all record one value): record with the driver's intensities on "
             "(ROS LaserScan intensities, a PCD intensity field)";
    return true;
  }
  if (e == Effect::landmark_bias) {
    r.identifiable = false;
    r.applicable = true;
    r.p_value = r.p_holm = r.score_p_value = kNaN;
    r.information_ratio = 0.0;
    r.standard_error = kInf;
    r.note = "an offset of one surface moves its fitted wall line as a whole: each line absorbs it";
    return true;
  }
  return false;
}

/// Correlation over the beams (weighted by their readings) of darkness and ln range: a time-of-flight
/// sensor without intensity compensation returns weaker from farther, and the two covariates then
/// say the same.
double StaticDiagnosis::darkRangeCorrelation() const {
  double n = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  for (std::size_t k = 0; k < d_.bins.size(); ++k) {
    if (f0_[k].n == 0 || !std::isfinite(d_.bins[k].intensity)) continue;
    const double w = static_cast<double>(d_.bins[k].idx.size()), x = d_.bins[k].dark, y = std::log(std::max(f0_[k].m, 1e-3));
    n += w;
    sx += w * x;
    sy += w * y;
    sxx += w * x * x;
    syy += w * y * y;
    sxy += w * x * y;
  }
  const double vx = sxx - sx * sx / std::max(n, 1.0), vy = syy - sy * sy / std::max(n, 1.0);
  return vx > 0.0 && vy > 0.0 ? (sxy - sx * sy / n) / std::sqrt(vx * vy) : 0.0;
}

void StaticDiagnosis::setIdentifiability(CandidateResult& r) const {
  const Effect e = r.effect;
  if (e == Effect::incidence_bias) {
    r.standard_error = wb_.ok ? wb_.b_se : kInf;
    r.identifiable = a0_identified_ && wb_.ok && r.standard_error < std::max(0.01, std::abs(wb_.b) / 4.0);
    if (!r.identifiable)
      r.note = a0_identified_ ? "bends the walls almost as a range offset does: give the offset (--range-offset) from a reference distance"
                              : "too few straight walls, or walls seen over too narrow a range of incidence";
  } else if (e == Effect::incidence_noise || e == Effect::range_noise_law || e == Effect::dark_surface) {
    // The exponent's standard error from the spread of its covariate over the bins (the score's
    // information for a log-linear variance: n var(g) / 2).
    double mm = 0.0, m2 = 0.0, n = 0.0;
    for (const auto& b : d_.bins) {
      if (e == Effect::incidence_noise && !b.inc_known) continue;
      const double g = e == Effect::incidence_noise ? -std::log(b.cos_inc)
                       : e == Effect::dark_surface  ? b.dark
                                                    : std::log(std::max(f0_[static_cast<std::size_t>(&b - d_.bins.data())].m, 1e-3));
      mm += g;
      m2 += g * g;
      n += static_cast<double>(b.idx.size());
    }
    const double nbins = static_cast<double>(d_.bins.size());
    const double var = nbins > 0 ? std::max(m2 / nbins - std::pow(mm / nbins, 2), 0.0) : 0.0;
    r.information_ratio = var / (m2 / std::max(nbins, 1.0) + 1e-4);
    r.standard_error = var > 0.0 ? 1.0 / std::sqrt(2.0 * n * var) : kInf;
    r.identifiable = r.standard_error < 0.5;
    if (!r.identifiable)
      r.note = e == Effect::incidence_noise ? "no spread of incidence angles"
               : e == Effect::dark_surface  ? "no spread of intensities"
                                            : "no spread of ranges";
    if (r.identifiable && e == Effect::dark_surface && std::abs(darkRangeCorrelation()) > kConfounded) {
      r.identifiable = false;
      r.note = "the intensity follows the range on this recording (correlation " + std::to_string(darkRangeCorrelation()) +
               "): a dark surface cannot be told from the range law; record surfaces of different reflectivity at the same "
               "distance";
    }
  } else if (e == Effect::range_drift && window_ > 0) {
    r.identifiable = false;
    r.note = "each window of scans has its own time trend per beam (the sensor moved), which absorbs a drift";
  } else if (e == Effect::mixed_pixels) {
    r.identifiable = edges_ >= 3;
    if (!r.identifiable) r.note = "fewer than 3 beams at depth discontinuities";
  }
}

void StaticDiagnosis::setEstimates(CandidateResult& r, const Model& fm) const {
  const Effect e = r.effect;
  if (e == Effect::incidence_noise) r.estimates["incidence_noise_exponent"] = fm.gamma;
  if (e == Effect::range_noise_law) r.estimates["noise_exponent"] = fm.kappa;
  if (e == Effect::dark_surface) {
    r.estimates["dark_noise_exponent"] = fm.delta;
    r.estimates["dark_reference_intensity"] = d_.i_ref;
    r.estimates["darkness_range_correlation"] = darkRangeCorrelation();
  }
  if (e == Effect::range_drift) {
    r.estimates["range_drift_m_per_scan"] = fm.drift;
    r.estimates["range_drift_over_recording_m"] = fm.drift * static_cast<double>(data_.scans - 1);
  }
  if (e == Effect::mixed_pixels) r.estimates["mixed_pixel_fraction"] = fm.mixed;
  if (e == Effect::heavy_tails) r.estimates["student_dof"] = fm.dof;
  if (e == Effect::quantisation) {
    r.estimates["grid_m"] = fm.q;
    r.estimates["noise_scale_unrounded"] = fm.sigma_e;  // sigma_e of sigma_e |m|^kappa before the rounding
  }
  if (e == Effect::incidence_bias) {
    r.estimates["incidence_bias_m"] = wb_.b;
    r.estimates["alpha0_with_it_m"] = wb_.alpha0;
  }
}

/// How close simulations come to the measured residuals: KS distance of z, per-bin variances.
Closeness StaticDiagnosis::closenessOf(const std::vector<ResidualRecord>& measured, const SimSample& sim) const {
  Closeness c;
  std::vector<double> mz;
  for (const auto& r : measured) mz.push_back(r.z);
  c.ks_distance = ksDistance(mz, sim.z);
  std::vector<double> logs;
  for (std::size_t k = 0; k < d_.bins.size(); ++k) {
    if (f0_[k].n == 0 || sim.var[k].empty() || !(f0_[k].s2 > 0.0)) continue;
    double mv = 0.0;
    for (double v : sim.var[k]) mv += v / static_cast<double>(sim.var[k].size());
    if (!(mv > 0.0)) continue;
    logs.push_back(std::abs(std::log(f0_[k].s2 / mv)));
  }
  c.groups = logs.size();
  c.variance_ratio_median_abs_log = logs.empty() ? 0.0 : upperMedian(logs);
  return c;
}

/// The named effect's model: its scene keys, and its simulation refitted with the baseline.
void StaticDiagnosis::extend(std::size_t c, DiagnosisResult& out) const {
  const Model& fm = full_[c];
  RangeEffects fx;
  Model sim_model = base0_;
  const Effect e = candidates_[c];
  if (e == Effect::incidence_noise) fx.incidence_noise_exponent = fm.gamma;
  if (named_by_tails_ && e == Effect::incidence_noise && robust_.count(e)) fx.incidence_noise_exponent = robust_.at(e);
  if (e == Effect::range_drift) {
    fx.range_drift_m_per_scan = fm.drift;
    fx.range_drift_reference_scan = d_.t_mean;  // the fit's drift is c (t - t_mean)
  }
  if (e == Effect::mixed_pixels) fx.mixed_pixel_fraction = fm.mixed;
  if (e == Effect::dark_surface) {
    fx.dark_noise_exponent = named_by_tails_ && robust_.count(e) ? robust_.at(e) : fm.delta;
    fx.dark_reference_intensity = d_.i_ref;
  }
  if (e == Effect::heavy_tails) fx.noise_student_dof = std::max(fm.dof, 2.1);
  if (e == Effect::quantisation) fx.range_resolution_m = fm.q;
  if (e == Effect::range_noise_law) sim_model.kappa = named_by_tails_ && robust_.count(e) ? robust_.at(e) : fm.kappa;
  sim_model.sigma_e = fm.sigma_e;
  // Named from the tails: the core noise fitted beside the contamination (its wild readings are
  // not simulated: the simulator has no covariate-dependent contamination).
  if (named_by_tails_ && robust_sigma_.count(e)) sim_model.sigma_e = robust_sigma_.at(e);
  WallFit w_sim = w0_;
  if (e == Effect::incidence_bias && wb_.ok) {
    w_sim = wb_;
    fx.incidence_bias_m = wb_.b;
  }
  const double a0 = w_sim.ok ? w_sim.alpha0 : 0.0;
  out.extended_bias_alpha = {a0, 1.0};
  setSceneKeys(out, a0, sim_model, fx);
  SimSample ext;
  ext.var.resize(d_.bins.size());
  for (int b = 0; b < config_.closeness_replicas; ++b) {
    const Data rep = simulateStatic(d_, f0_, w_sim, sim_model, deriveSeed(config_.seed, 6000 + static_cast<std::uint64_t>(b)), fx);
    std::vector<BinFit> fr;
    const Model mr = fitModel(rep, {}, Flags{}, 0.0, fr);
    const auto rec = recordsOf(rep, fr, mr);
    ext.add(rec, fr);
    if (b == 0) out.simulated_extended = rec;
  }
  out.closeness_extended = closenessOf(out.measured, ext);
}

void StaticDiagnosis::setSceneKeys(DiagnosisResult& out, double a0, const Model& sim_model, const RangeEffects& fx) const {
  auto& keys = out.scene_keys;
  keys["sensor.bias_alpha[0]"] = a0;
  keys["sensor.bias_alpha[1]"] = 1.0;
  if (sim_model.kappa != 2.0) keys["sensor.noise.exponent (kind power)"] = sim_model.kappa;
  keys["sensor.noise.sigma_e"] = sim_model.sigma_e;
  if (fx.incidence_noise_exponent != 0.0) keys[info(Effect::incidence_noise).scene_key] = fx.incidence_noise_exponent;
  if (fx.incidence_bias_m != 0.0) keys[info(Effect::incidence_bias).scene_key] = fx.incidence_bias_m;
  if (fx.range_drift_m_per_scan != 0.0) {
    keys[info(Effect::range_drift).scene_key] = fx.range_drift_m_per_scan;
    keys["sensor.effects.range_drift_reference_scan"] = fx.range_drift_reference_scan;
  }
  if (fx.mixed_pixel_fraction != 0.0) keys[info(Effect::mixed_pixels).scene_key] = fx.mixed_pixel_fraction;
  if (fx.noise_student_dof != 0.0) keys[info(Effect::heavy_tails).scene_key] = fx.noise_student_dof;
  if (fx.range_resolution_m != 0.0) keys[info(Effect::quantisation).scene_key] = fx.range_resolution_m;
  if (fx.dark_noise_exponent != 0.0) {
    keys[info(Effect::dark_surface).scene_key] = fx.dark_noise_exponent;
    keys["sensor.effects.dark_reference_intensity"] = fx.dark_reference_intensity;
  }
}

}  // namespace

std::vector<Effect> staticCandidates() { return candidateList(DiagnoseConfig{}, DiagnoseMode::static_scene); }

DiagnosisResult diagnoseStatic(const StaticScans& data, const DiagnoseConfig& config, std::vector<WallLine>* walls_out) {
  config.validate();
  DiagnosisResult out;
  out.mode = DiagnoseMode::static_scene;
  out.seed = config.seed;
  out.replicas = config.replicas;
  out.folds = config.folds;
  out.scans = data.scans;
  out.stops = 1;
  out.readings = data.readings.size();
  const std::vector<Effect> candidates = candidateList(config, DiagnoseMode::static_scene);
  StaticDiagnosis problem(data, config, candidates, walls_out);
  runDiagnosis(problem, config, candidates, out);
  return out;
}

}  // namespace lidarcal::diagnosis
