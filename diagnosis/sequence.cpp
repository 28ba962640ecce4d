#include "diagnosis/sequence.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

#include <Eigen/Dense>

#include "calibration/calibrate.hpp"
#include "diagnosis/stats.hpp"
#include "calibration/evaluation.hpp"
#include "calibration/inversion.hpp"
#include "calibration/joint_refinement.hpp"
#include "common/rng.hpp"
#include "simulation/landmark_level.hpp"

namespace lidarcal::diagnosis {
// The diagnosis refits with the calibration stages (joint refinement, range model, inversion).
using namespace lidarcal::calibration;
namespace {

constexpr double kClip = 3.0;  // Huber clipping of standardised residuals in the score statistics
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<std::string> allCandidates() {
  return {effect::kIncidenceNoise, effect::kIncidenceBias, effect::kLandmarkBias, effect::kHeadingError,
          effect::kRangeDrift,     effect::kMixedPixels,   effect::kAngleOffset,  effect::kRangeNoiseLaw,
          effect::kOdometryScale};
}

/// The score statistic that tests each candidate (a member of the battery).
const char* statisticOf(const std::string& e) {
  if (e == effect::kIncidenceNoise) return "spread_vs_incidence";
  if (e == effect::kIncidenceBias) return "residual_vs_incidence";
  if (e == effect::kLandmarkBias) return "landmark_identity";
  if (e == effect::kHeadingError) return "heading_within_stop";
  if (e == effect::kRangeDrift) return "residual_vs_time";
  if (e == effect::kMixedPixels) return "edge_excess";
  if (e == effect::kAngleOffset) return "path_rotation";
  if (e == effect::kRangeNoiseLaw) return "spread_vs_range";
  if (e == effect::kOdometryScale) return "path_scale";
  return "";
}

JointConfig effectConfig(JointConfig c, const std::string& e) {
  JointEffects& fx = c.effects;
  if (e == effect::kIncidenceNoise) fx.incidence_noise = true;
  else if (e == effect::kIncidenceBias) fx.incidence_bias = true;
  else if (e == effect::kLandmarkBias) fx.landmark_offsets = true;
  else if (e == effect::kHeadingError) fx.estimate_heading = true;
  else if (e == effect::kRangeDrift) fx.drift = true;
  else if (e == effect::kMixedPixels) fx.mixed_pixels = true;
  else if (e == effect::kAngleOffset) fx.angle_offset = true;
  else if (e == effect::kRangeNoiseLaw) fx.noise_exponent = true;
  else if (e == effect::kOdometryScale) fx.odometry_scale = true;
  else throw std::invalid_argument("diagnose: unknown effect '" + e + "' for a sequence");
  return c;
}

JointInit initFrom(const JointResult& r) {
  JointInit i;
  i.poses = r.poses;
  i.centres = r.centres;
  i.radius_m = r.radius_m;
  i.model = r.model;
  i.effects = r.effects;
  return i;
}

LandmarkObservations subset(const LandmarkObservations& obs, const std::vector<bool>& keep) {
  LandmarkObservations out;
  out.commanded = obs.commanded;
  out.landmark_radius_m = obs.landmark_radius_m;
  out.range_min_m = obs.range_min_m;
  out.range_max_m = obs.range_max_m;
  for (std::size_t i = 0; i < obs.sightings.size(); ++i)
    if (keep[i]) out.sightings.push_back(obs.sightings[i]);
  return out;
}

/// Fold of each sighting: scan position within its stop modulo K, or (stop + landmark) mod K
/// when some stop has a single scan (its pose must be learnt from its other sightings).
std::vector<int> folds(const LandmarkObservations& obs, int k) {
  std::map<std::size_t, std::set<std::size_t>> scans_of_stop;
  for (const auto& s : obs.sightings) scans_of_stop[s.stop].insert(s.scan);
  bool by_scan = true;
  for (const auto& [stop, scans] : scans_of_stop) by_scan = by_scan && scans.size() >= 2;
  std::map<std::size_t, int> position;
  for (const auto& [stop, scans] : scans_of_stop) {
    int i = 0;
    for (std::size_t scan : scans) position[scan] = i++;
  }
  std::vector<int> f(obs.sightings.size());
  for (std::size_t i = 0; i < obs.sightings.size(); ++i) {
    const auto& s = obs.sightings[i];
    f[i] = by_scan ? position[s.scan] % k : static_cast<int>((s.stop + static_cast<std::size_t>(s.landmark)) % static_cast<std::size_t>(k));
  }
  return f;
}

/// Distance along a ray to a circle and its derivatives (see rayCircleDistance); the square
/// root is kept away from 0 near the tangent like the incidence (clampCosIncidence).
struct RayGradient {
  double d = 0.0, dcx = 0.0, dcy = 0.0, dr = 0.0, da = 0.0;
};

RayGradient rayGradient(double px, double py, double a, double cx, double cy, double r) {
  RayGradient g;
  const double c = std::cos(a), s = std::sin(a);
  const double dx = cx - px, dy = cy - py;
  const double along = dx * c + dy * s, perp = dy * c - dx * s;
  const double disc = r * r - perp * perp;
  g.d = rayCircleDistance(px, py, a, cx, cy, r);
  if (disc <= 0.0) {
    g.dcx = c;
    g.dcy = s;
    g.da = perp;
    return g;
  }
  const double sq = std::max(std::sqrt(disc), 0.05 * r);
  g.dcx = c - perp / sq * s;
  g.dcy = s + perp / sq * c;
  g.dr = -r / sq;
  g.da = perp * (1.0 - along / sq);
  return g;
}

/// Per-reading quantities the statistics need, under a fit.
struct Row {
  JointReading r;
  double z = 0.0, psi = 0.0, dmu_da = 0.0;
};

std::vector<Row> rows(const LandmarkObservations& obs, const JointResult& fit, const JointConfig& cfg) {
  std::vector<Row> out;
  for (const auto& r : evaluateJoint(obs, fit, cfg)) {
    Row w;
    w.r = r;
    w.z = (r.y_m - r.mean_m) / r.sigma_m;
    w.psi = huberPsi(w.z, kClip);
    const Pose2& p = fit.poses[r.stop];
    const auto& c = fit.centres.at(r.landmark);
    const RayGradient g = rayGradient(p.x_m, p.y_m, p.yaw_rad + r.angle_rad + fit.effects.angle_offset_rad, c.x(), c.y(),
                                      fit.radius_m);
    w.dmu_da = fit.model.bias.derivative(g.d) * g.da;
    out.push_back(w);
  }
  return out;
}

/// Score of a mean-type effect with covariate x (metres of reading per unit parameter).
double meanScore(const std::vector<Row>& rs, const std::vector<double>& x) {
  std::vector<double> psi(rs.size()), xs(rs.size());
  for (std::size_t i = 0; i < rs.size(); ++i) {
    psi[i] = rs[i].psi;
    xs[i] = x[i] / rs[i].r.sigma_m;
  }
  return diagnosis::meanScore(psi, xs);
}

/// Score of a variance-type effect with covariate g (log of the factor on sigma per unit).
double spreadScore(const std::vector<Row>& rs, const std::vector<double>& g) {
  std::vector<double> z(rs.size());
  for (std::size_t i = 0; i < rs.size(); ++i) z[i] = rs[i].z;
  return diagnosis::spreadScore(z, g);
}

/// Sum over groups of (group score)^2 / information, with the overall mean removed (the bias
/// polynomial's alpha_0 absorbs it when `centre`), as a cube root (Wilson-Hilferty).
double groupChi2(const std::vector<Row>& rs, const std::vector<int>& group, const std::vector<double>& x, bool centre) {
  std::map<int, std::pair<double, double>> g;  // score, information
  double u_all = 0.0, i_all = 0.0;
  for (std::size_t i = 0; i < rs.size(); ++i) {
    const double xs = x[i] / rs[i].r.sigma_m;
    g[group[i]].first += rs[i].psi * xs;
    g[group[i]].second += xs * xs;
    u_all += rs[i].psi * xs;
    i_all += xs * xs;
  }
  double chi2 = 0.0;
  int n = 0;
  for (const auto& [k, v] : g) {
    if (!(v.second > 0.0)) continue;
    const double u = centre && i_all > 0.0 ? v.first - v.second * u_all / i_all : v.first;
    chi2 += u * u / v.second;
    ++n;
  }
  return cubeRootChi2(chi2, std::max(centre ? n - 1 : n, 1));
}

/// Residuals of a polynomial trend in x of order up to `order` (weighted least squares), so
/// that a covariate is tested beyond what the bias polynomial already absorbs.
std::vector<double> orthogonalise(const std::vector<double>& x, const std::vector<double>& d, const std::vector<double>& w,
                                  int order) {
  const int p = order + 1;
  Eigen::MatrixXd a(static_cast<Eigen::Index>(x.size()), p);
  Eigen::VectorXd b(static_cast<Eigen::Index>(x.size()));
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double sw = std::sqrt(w[i]);
    double v = 1.0;
    for (int j = 0; j < p; ++j) {
      a(static_cast<Eigen::Index>(i), j) = sw * v;
      v *= d[i];
    }
    b(static_cast<Eigen::Index>(i)) = sw * x[i];
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
  std::vector<double> out(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    double v = 1.0, fit = 0.0;
    for (int j = 0; j < p; ++j) {
      fit += c(j) * v;
      v *= d[i];
    }
    out[i] = x[i] - fit;
  }
  return out;
}

/// Every statistic of the battery (and the candidates' scores) under a baseline fit.
std::map<std::string, double> statistics(const LandmarkObservations& obs, const JointResult& fit, const std::vector<Row>& rs,
                                         const JointConfig& cfg) {
  std::map<std::string, double> st;
  const std::size_t n = rs.size();
  if (n == 0) return st;
  std::vector<double> d(n), w(n), x(n), g(n);
  std::vector<int> grp(n);
  for (std::size_t i = 0; i < n; ++i) {
    d[i] = rs[i].r.d_m;
    w[i] = 1.0 / (rs[i].r.sigma_m * rs[i].r.sigma_m);
  }
  const int order = fit.model.bias.order();
  // Range: the residuals' trend beyond the bias polynomial, and their spread (noise law).
  for (std::size_t i = 0; i < n; ++i) x[i] = std::pow(d[i], order + 1);
  st["residual_vs_range"] = meanScore(rs, orthogonalise(x, d, w, order));
  for (std::size_t i = 0; i < n; ++i) g[i] = std::log(std::max(std::abs(fit.model.bias(d[i])), 1e-3));
  st["spread_vs_range"] = spreadScore(rs, g);
  // Incidence.
  for (std::size_t i = 0; i < n; ++i) x[i] = 1.0 - rs[i].r.cos_incidence;
  st["residual_vs_incidence"] = meanScore(rs, orthogonalise(x, d, w, 0));
  for (std::size_t i = 0; i < n; ++i) g[i] = -std::log(rs[i].r.cos_incidence);
  st["spread_vs_incidence"] = spreadScore(rs, g);
  // Position within the object: outermost beams against the others.
  {
    double pos_edge = 0, neg_edge = 0, n_edge = 0, pos_in = 0, neg_in = 0, n_in = 0, s_edge = 0, s_in = 0;
    for (const auto& r : rs) {
      const double z2 = std::min(r.z * r.z, kClip * kClip);
      if (r.r.edge) {
        n_edge += 1;
        pos_edge += r.z > kClip;
        neg_edge += r.z < -kClip;
        s_edge += z2;
      } else {
        n_in += 1;
        pos_in += r.z > kClip;
        neg_in += r.z < -kClip;
        s_in += z2;
      }
    }
    const double expected = n_in > 0 ? n_edge * (pos_in - neg_in) / n_in : 0.0;
    st["edge_excess"] = n_edge > 0 ? (pos_edge - neg_edge - expected) / std::sqrt(n_edge) : 0.0;
    st["edge_vs_centre_spread"] = (n_edge > 0 && n_in > 0) ? s_edge / n_edge - s_in / n_in : 0.0;
  }
  // Landmark identity (offsets beyond the common bias), stop identity.
  std::vector<double> one(n, 1.0);
  for (std::size_t i = 0; i < n; ++i) grp[i] = rs[i].r.landmark;
  st["landmark_identity"] = groupChi2(rs, grp, one, true);
  for (std::size_t i = 0; i < n; ++i) grp[i] = static_cast<int>(rs[i].r.stop);
  st["stop_identity"] = groupChi2(rs, grp, one, true);
  // Rotations: per stop (heading errors) and common (zero-angle offset).
  for (std::size_t i = 0; i < n; ++i) x[i] = rs[i].dmu_da;
  st["heading_within_stop"] = groupChi2(rs, grp, x, false);
  st["common_rotation"] = meanScore(rs, x);
  // Time.
  double tm = 0.0, tw = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    tm += w[i] * static_cast<double>(rs[i].r.scan);
    tw += w[i];
  }
  for (std::size_t i = 0; i < n; ++i) x[i] = static_cast<double>(rs[i].r.scan) - tm / tw;
  st["residual_vs_time"] = meanScore(rs, x);
  // Bearing in the sensor frame: first harmonics.
  {
    std::vector<double> xc(n), xs(n);
    for (std::size_t i = 0; i < n; ++i) {
      xc[i] = std::cos(rs[i].r.angle_rad);
      xs[i] = std::sin(rs[i].r.angle_rad);
    }
    const double a = meanScore(rs, orthogonalise(xc, d, w, 0)), b = meanScore(rs, orthogonalise(xs, d, w, 0));
    st["residual_vs_bearing"] = cubeRootChi2(a * a + b * b, 2.0);
  }
  // The refined path against the commanded one, about its centroid: rotated (a zero-angle
  // offset turns the path the data see against the headings) or stretched (step length).
  {
    double cx = 0.0, cy = 0.0;
    const std::size_t k_stops = std::min(fit.poses.size(), obs.commanded.size());
    for (std::size_t k = 0; k < k_stops; ++k) {
      cx += obs.commanded[k].x_m / static_cast<double>(k_stops);
      cy += obs.commanded[k].y_m / static_cast<double>(k_stops);
    }
    double rot = 0.0, str = 0.0, info = 0.0;
    for (std::size_t k = 0; k < k_stops; ++k) {
      const double ex = obs.commanded[k].x_m - cx, ey = obs.commanded[k].y_m - cy;
      const double dx = fit.poses[k].x_m - obs.commanded[k].x_m, dy = fit.poses[k].y_m - obs.commanded[k].y_m;
      rot += ex * dy - ey * dx;
      str += ex * dx + ey * dy;
      info += ex * ex + ey * ey;
    }
    st["path_rotation"] = info > 0.0 ? rot / (cfg.sigma_s_m * std::sqrt(info)) : 0.0;
    st["path_scale"] = info > 0.0 ? str / (cfg.sigma_s_m * std::sqrt(info)) : 0.0;
  }
  // Sighting bearings: shared shifts within a stop (F ratio of stop means, log).
  {
    std::map<std::size_t, std::vector<double>> by_stop;
    for (const auto& s : obs.sightings) {
      auto c = fit.centres.find(s.landmark);
      if (c == fit.centres.end() || s.stop >= fit.poses.size()) continue;
      const Pose2& p = fit.poses[s.stop];
      const double predicted =
          std::atan2(c->second.y() - p.y_m, c->second.x() - p.x_m) - p.yaw_rad - fit.effects.angle_offset_rad;
      by_stop[s.stop].push_back(wrapAngle(s.bearing_rad - predicted));
    }
    double grand = 0.0, total = 0.0;
    for (const auto& [k, v] : by_stop)
      for (double b : v) {
        grand += b;
        total += 1.0;
      }
    grand /= std::max(total, 1.0);
    double between = 0.0, within = 0.0;
    for (const auto& [k, v] : by_stop) {
      double m = 0.0;
      for (double b : v) m += b / static_cast<double>(v.size());
      between += static_cast<double>(v.size()) * (m - grand) * (m - grand);
      for (double b : v) within += (b - m) * (b - m);
    }
    const double dfb = static_cast<double>(by_stop.size()) - 1.0, dfw = total - static_cast<double>(by_stop.size());
    st["bearing_within_stop_correlation"] =
        (dfb > 0 && dfw > 0 && within > 0) ? std::log((between / dfb) / (within / dfw)) : 0.0;
  }
  // Tails and quantisation.
  {
    double m2 = 0.0, m4 = 0.0;
    for (const auto& r : rs) {
      m2 += r.z * r.z;
      m4 += r.z * r.z * r.z * r.z;
    }
    m2 /= static_cast<double>(n);
    m4 /= static_cast<double>(n);
    st["tail_weight"] = m4 / (m2 * m2) - 3.0;
    std::vector<double> y(n);
    for (std::size_t i = 0; i < n; ++i) y[i] = rs[i].r.y_m;
    st["quantisation_1mm"] = gridResultant(y, 1e-3);
  }
  return st;
}

const std::vector<StatisticInfo>& statInfo() {
  static const std::vector<StatisticInfo> info = {
      {"residual_vs_range", "range", "score of a range trend of the residuals beyond the bias polynomial (order n + 1), ~N(0,1)", true},
      {"spread_vs_range", "range", "score of the noise growing with log f(d) beyond the squared law (clipped squared residuals), ~N(0,1)", true},
      {"residual_vs_incidence", "incidence angle", "score of the residuals against 1 - cos(incidence), ~N(0,1)", true},
      {"spread_vs_incidence", "incidence angle", "score of the noise growing with -ln cos(incidence), ~N(0,1)", true},
      {"edge_excess", "position within the object", "positive minus negative |z| > 3 residuals on the outermost beams, beyond the inner beams' rate, per sqrt(edge beams)", false},
      {"edge_vs_centre_spread", "position within the object", "mean clipped z^2 on the outermost beams minus on the inner beams", true},
      {"landmark_identity", "landmark", "cube root of chi^2 / dof of the per-landmark mean residuals (overall mean removed)", false},
      {"stop_identity", "stop index", "cube root of chi^2 / dof of the per-stop mean residuals (overall mean removed)", false},
      {"heading_within_stop", "stop index", "cube root of chi^2 / dof of per-stop rotation scores (a heading shared by all beams of a stop)", false},
      {"common_rotation", "bearing", "score of one rotation shared by every beam (zero-angle offset), ~N(0,1)", true},
      {"residual_vs_time", "scan index", "score of a linear trend of the residuals over the scans, ~N(0,1)", true},
      {"residual_vs_bearing", "bearing", "cube root of chi^2 / 2 of the residuals against cos and sin of the beam angle", false},
      {"path_rotation", "stop index", "rotation of the refined stop positions against the commanded path about its centroid, over the position prior, ~N(0,1)", true},
      {"path_scale", "stop index", "stretch of the refined stop positions against the commanded path about its centroid, over the position prior, ~N(0,1)", true},
      {"bearing_within_stop_correlation", "stop index", "ln F of the sighting bearing residuals between stops against within stops", false},
      {"tail_weight", "residual", "excess kurtosis of the standardised residuals", false},
      {"quantisation_1mm", "reading", "resultant length of the readings' phase on a 1 mm grid (1: on the grid)", false},
  };
  return info;
}

/// Landmark-level simulation of the measured geometry from a fit (ids mapped to the fit's).
struct ReplicaPlan {
  simulation::LandmarkLevelConfig config;
  std::vector<int> ids;                           ///< simulated landmark l + 1 -> data id
  std::set<std::pair<std::size_t, int>> present;  ///< (scan, data landmark id) pairs of the data
};

ReplicaPlan replicaPlan(const LandmarkObservations& obs, const JointResult& fit, bool radius_known) {
  ReplicaPlan plan;
  auto& c = plan.config;
  for (const auto& [id, centre] : fit.centres) {
    Cylinder cyl{centre.x(), centre.y(), fit.radius_m};
    auto o = fit.effects.landmark_offset_m.find(id);
    if (o != fit.effects.landmark_offset_m.end()) cyl.range_offset_m = o->second;
    c.landmarks.push_back(cyl);
    plan.ids.push_back(id);
  }
  std::map<std::size_t, std::pair<std::size_t, std::size_t>> scans;  // stop -> (first, last)
  for (const auto& s : obs.sightings) {
    plan.present.insert({s.scan, s.landmark});
    auto it = scans.find(s.stop);
    if (it == scans.end()) scans[s.stop] = {s.scan, s.scan};
    else it->second = {std::min(it->second.first, s.scan), std::max(it->second.second, s.scan)};
  }
  for (std::size_t k = 0; k < obs.commanded.size(); ++k) {
    TruthStop t;
    t.commanded = obs.commanded[k];
    t.actual = fit.poses[k];
    auto it = scans.find(k);
    if (it != scans.end()) {
      t.first_scan = it->second.first;
      t.scans = it->second.second - it->second.first + 1;
    }
    c.stops.push_back(t);
  }
  c.model = fit.model;
  c.model.range_min_m = obs.range_min_m;
  c.model.range_max_m = obs.range_max_m;
  c.sigma_theta_rad = fit.sigma_theta_rad;
  c.beams = true;
  c.publish_radius = radius_known;
  c.effects.incidence_noise_exponent = fit.effects.incidence_noise_exponent;
  c.effects.incidence_bias_m = fit.effects.incidence_bias_m;
  c.effects.range_drift_m_per_scan = fit.effects.drift_m_per_scan;
  c.model.bias.alpha[0] -= fit.effects.drift_m_per_scan * fit.effects.drift_reference_scan;
  c.effects.mixed_pixel_fraction = fit.effects.mixed_pixel_fraction;
  c.mount_yaw_rad = fit.effects.angle_offset_rad;
  if (c.effects.mixed_pixel_fraction > 0.0) {
    // The fitted mixed pixels read uniformly up to the window's end: a background that far.
    double cx = 0.0, cy = 0.0;
    for (const auto& p : obs.commanded) {
      cx += p.x_m / static_cast<double>(obs.commanded.size());
      cy += p.y_m / static_cast<double>(obs.commanded.size());
    }
    const double r = fit.window_max_m;
    c.walls = {Segment{cx - r, cy - r, cx + r, cy - r}, Segment{cx + r, cy - r, cx + r, cy + r},
               Segment{cx + r, cy + r, cx - r, cy + r}, Segment{cx - r, cy + r, cx - r, cy - r}};
  }
  // Beam grid of the data: the step between neighbouring beams, and its origin.
  std::vector<double> steps, origins;
  for (const auto& s : obs.sightings)
    for (std::size_t j = 1; j < s.beams.size(); ++j) {
      const auto db = static_cast<double>(s.beams[j].beam) - static_cast<double>(s.beams[j - 1].beam);
      if (db >= 1.0 && db <= 3.0) steps.push_back(wrapAngle(s.beams[j].angle_rad - s.beams[j - 1].angle_rad) / db);
    }
  if (!steps.empty()) {
    std::nth_element(steps.begin(), steps.begin() + static_cast<long>(steps.size() / 2), steps.end());
    c.angle_increment_rad = steps[steps.size() / 2];
  }
  for (const auto& s : obs.sightings)
    for (const auto& b : s.beams) origins.push_back(wrapAngle(b.angle_rad - static_cast<double>(b.beam) * c.angle_increment_rad));
  if (!origins.empty()) {
    std::nth_element(origins.begin(), origins.begin() + static_cast<long>(origins.size() / 2), origins.end());
    c.angle_min_rad = origins[origins.size() / 2];
  }
  return plan;
}

/// How a replica's stop poses are drawn: around the commanded path (scaled by 1 + scale), with
/// the model's position and heading scatter (seed 000 eq. 8).
struct PoseNoise {
  double sigma_s_m = 0.0, sigma_psi_rad = 0.0, scale = 0.0;
};

PoseNoise poseNoise(const JointResult& fit, const JointConfig& cfg) {
  PoseNoise n;
  n.sigma_s_m = cfg.sigma_s_m;
  n.sigma_psi_rad = cfg.effects.estimate_heading ? fit.effects.heading_rms_rad : 0.0;
  n.scale = fit.effects.odometry_scale;
  return n;
}

LandmarkObservations simulateReplica(ReplicaPlan plan, const LandmarkObservations& obs, const PoseNoise& noise,
                                     std::uint64_t seed, std::vector<std::vector<double>>* truth = nullptr) {
  // The stop poses are redrawn: the baseline says they scatter independently around the
  // commanded ones, and whatever the fitted poses show beyond that is evidence against it.
  auto rng = makeRng(seed, 0x9053ULL);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Pose2& c0 = obs.commanded.front();
  for (std::size_t k = 0; k < plan.config.stops.size(); ++k) {
    const Pose2& c = obs.commanded[k];
    Pose2& a = plan.config.stops[k].actual;
    a.x_m = c0.x_m + (1.0 + noise.scale) * (c.x_m - c0.x_m) + noise.sigma_s_m * normal(rng);
    a.y_m = c0.y_m + (1.0 + noise.scale) * (c.y_m - c0.y_m) + noise.sigma_s_m * normal(rng);
    a.yaw_rad = wrapAngle(c.yaw_rad + noise.sigma_psi_rad * normal(rng));
  }
  auto sample = simulation::simulateLandmarkLevel(plan.config, seed);
  LandmarkObservations out;
  out.commanded = obs.commanded;
  out.landmark_radius_m = obs.landmark_radius_m;
  out.range_min_m = obs.range_min_m;
  out.range_max_m = obs.range_max_m;
  for (std::size_t i = 0; i < sample.obs.sightings.size(); ++i) {
    Sighting s = sample.obs.sightings[i];
    s.landmark = plan.ids.at(static_cast<std::size_t>(s.landmark - 1));
    if (!plan.present.count({s.scan, s.landmark})) continue;
    out.sightings.push_back(std::move(s));
    if (truth) truth->push_back(sample.true_range_m[i]);
  }
  return out;
}

/// Held-out log-likelihood of the odometry: for each stop, the commanded position predicted from
/// everything but its own odometry (its readings locate it in the world the other stops fix).
/// Linearised leave-one-out: with H the information of the stop's position from its readings
/// (heading profiled out when the model refines it), the position without its prior is
/// p + H^-1 (p - c) / sigma_s^2 and c is N(that, sigma_s^2 I + H^-1). c is the commanded position
/// (scaled by 1 + s with the odometry scale).
std::vector<double> odometryHeldOut(const LandmarkObservations& obs, const JointResult& fit, const JointConfig& cfg) {
  const std::size_t k_stops = fit.poses.size();
  std::vector<Eigen::Matrix3d> h(k_stops, Eigen::Matrix3d::Zero());
  for (const auto& r : evaluateJoint(obs, fit, cfg)) {
    const Pose2& p = fit.poses[r.stop];
    const auto& c = fit.centres.at(r.landmark);
    const RayGradient g = rayGradient(p.x_m, p.y_m, p.yaw_rad + r.angle_rad + fit.effects.angle_offset_rad, c.x(), c.y(),
                                      fit.radius_m);
    const double fp = fit.model.bias.derivative(g.d);
    const Eigen::Vector3d j(-fp * g.dcx, -fp * g.dcy, fp * g.da);
    h[r.stop] += j * j.transpose() / (r.sigma_m * r.sigma_m);
  }
  const double s2 = cfg.sigma_s_m * cfg.sigma_s_m;
  const Pose2& c0 = obs.commanded.front();
  const double scale = fit.effects.odometry_scale;
  std::vector<double> out(k_stops, 0.0);
  for (std::size_t k = 0; k < k_stops; ++k) {
    Eigen::Matrix2d hxy = h[k].topLeftCorner<2, 2>();
    if (cfg.effects.estimate_heading) {
      const double hpp = h[k](2, 2) + 1.0 / (cfg.sigma_psi_rad * cfg.sigma_psi_rad);
      hxy -= h[k].topRightCorner<2, 1>() * h[k].bottomLeftCorner<1, 2>() / hpp;
    }
    hxy.diagonal().array() += 1e-9;
    const Eigen::Matrix2d cov_data = hxy.inverse();
    const Eigen::Vector2d c(c0.x_m + (1.0 + scale) * (obs.commanded[k].x_m - c0.x_m),
                            c0.y_m + (1.0 + scale) * (obs.commanded[k].y_m - c0.y_m));
    const Eigen::Vector2d p(fit.poses[k].x_m, fit.poses[k].y_m);
    const Eigen::Vector2d pd = p + cov_data * (p - c) / s2;
    const Eigen::Matrix2d cov = s2 * Eigen::Matrix2d::Identity() + cov_data;
    const Eigen::Vector2d e = c - pd;
    out[k] = -std::log(2.0 * kPi) - 0.5 * std::log(cov.determinant()) - 0.5 * e.dot(cov.inverse() * e);
  }
  return out;
}

/// What the data can say about each effect once the baseline's parameters are free.
struct Identifiability {
  double ratio = 1.0;  ///< information kept after the nuisance parameters, trace(I_eff) / trace(I_raw)
  double se = 0.0;     ///< standard error of the effect's parameter(s) after them (RMS over components)
  double ref = 0.0;    ///< the smallest size worth naming (same unit); identifiable when se < ref
};

/// Mean-type effects: the model's Jacobian in the nuisance parameters (bias, radius when
/// estimated, centres, stop positions with their priors) and in the effect; I_eff is the
/// information on the effect left after profiling the nuisance out. Variance-type effects:
/// the variety of their covariate beyond a constant (the noise scale).
std::map<std::string, Identifiability> identifiability(const LandmarkObservations& obs, const JointResult& fit,
                                                       const std::vector<Row>& rs, const JointConfig& cfg) {
  const int na = fit.model.bias.order() + 1;
  std::map<int, int> lm;  // landmark id -> column index (x; y at +1)
  for (const auto& [id, c] : fit.centres) lm[id] = 0;
  const int k_stops = static_cast<int>(fit.poses.size());
  int col = na + (cfg.estimate_radius ? 1 : 0);
  for (auto& [id, c] : lm) {
    c = col;
    col += 2;
  }
  const int pose0 = col;
  const int p = pose0 + 2 * k_stops;
  const int n = static_cast<int>(rs.size());
  const int rows_total = n + 2 * k_stops;
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(rows_total, p);
  Eigen::VectorXd w = Eigen::VectorXd::Ones(rows_total);
  Eigen::MatrixXd x_lm = Eigen::MatrixXd::Zero(rows_total, std::max<int>(static_cast<int>(lm.size()) - 1, 1));
  Eigen::MatrixXd x_head = Eigen::MatrixXd::Zero(rows_total, k_stops);
  Eigen::MatrixXd x_drift = Eigen::MatrixXd::Zero(rows_total, 1), x_angle = x_drift, x_inc = x_drift, x_scale = x_drift;
  double tmean = 0.0, tmin = std::numeric_limits<double>::infinity(), tmax = -tmin;
  for (const auto& r : rs) {
    tmean += static_cast<double>(r.r.scan) / static_cast<double>(n);
    tmin = std::min(tmin, static_cast<double>(r.r.scan));
    tmax = std::max(tmax, static_cast<double>(r.r.scan));
  }
  for (int i = 0; i < n; ++i) {
    const auto& r = rs[static_cast<std::size_t>(i)].r;
    w(i) = 1.0 / (r.sigma_m * r.sigma_m);
    const Pose2& ps = fit.poses[r.stop];
    const auto& c = fit.centres.at(r.landmark);
    const RayGradient g = rayGradient(ps.x_m, ps.y_m, ps.yaw_rad + r.angle_rad + fit.effects.angle_offset_rad, c.x(), c.y(),
                                      fit.radius_m);
    const double fp = fit.model.bias.derivative(g.d);
    double v = 1.0;
    for (int a = 0; a < na; ++a) {
      j(i, a) = v;
      v *= g.d;
    }
    if (cfg.estimate_radius) j(i, na) = fp * g.dr;
    const int cc = lm.at(r.landmark);
    j(i, cc) = fp * g.dcx;
    j(i, cc + 1) = fp * g.dcy;
    const int pc = pose0 + 2 * static_cast<int>(r.stop);
    j(i, pc) = -fp * g.dcx;
    j(i, pc + 1) = -fp * g.dcy;
    const int li = static_cast<int>(std::distance(lm.begin(), lm.find(r.landmark)));
    if (li > 0) x_lm(i, li - 1) = 1.0;
    x_head(i, static_cast<int>(r.stop)) = fp * g.da;
    x_angle(i, 0) = fp * g.da;
    x_drift(i, 0) = static_cast<double>(r.scan) - tmean;
    x_inc(i, 0) = 1.0 - r.cos_incidence;
  }
  const Pose2& c0 = obs.commanded.front();
  for (int k = 0; k < k_stops; ++k) {
    const double inv = 1.0 / cfg.sigma_s_m;
    j(n + 2 * k, pose0 + 2 * k) = inv;
    j(n + 2 * k + 1, pose0 + 2 * k + 1) = inv;
    x_scale(n + 2 * k, 0) = -(obs.commanded[static_cast<std::size_t>(k)].x_m - c0.x_m) * inv;
    x_scale(n + 2 * k + 1, 0) = -(obs.commanded[static_cast<std::size_t>(k)].y_m - c0.y_m) * inv;
  }
  const Eigen::MatrixXd jw = j.transpose() * w.asDiagonal();
  Eigen::MatrixXd h = jw * j;
  // A ridge relative to each parameter's own information: an absolute one (scaled by the
  // largest diagonal) would pin the weakly informed nuisance directions and make an effect
  // that they absorb exactly (a step-length error with the radius free) look estimable.
  h.diagonal().array() *= 1.0 + 1e-9;
  h.diagonal().array() += 1e-300;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(h);
  auto assess = [&](const Eigen::MatrixXd& x, double ref) {
    Identifiability id;
    id.ref = ref;
    const Eigen::MatrixXd raw = x.transpose() * w.asDiagonal() * x;
    const Eigen::MatrixXd c = jw * x;
    Eigen::MatrixXd eff = raw - c.transpose() * ldlt.solve(c);
    const double tr = raw.trace();
    id.ratio = tr > 0.0 ? std::clamp(eff.trace() / tr, 0.0, 1.0) : 0.0;
    // Standard errors: diagonal of I_eff^-1 (a small ridge keeps a singular I_eff finite and huge).
    eff.diagonal().array() += 1e-12 * (raw.diagonal().array().abs().maxCoeff() + 1e-300);
    const Eigen::MatrixXd cov = eff.ldlt().solve(Eigen::MatrixXd::Identity(eff.rows(), eff.cols()));
    double s = 0.0;
    for (Eigen::Index i = 0; i < cov.rows(); ++i) s += std::max(cov(i, i), 0.0);
    id.se = std::sqrt(s / static_cast<double>(cov.rows()));
    if (!(tr > 0.0)) id.se = std::numeric_limits<double>::infinity();
    return id;
  };
  std::map<std::string, Identifiability> out;
  if (lm.size() >= 2) out[effect::kLandmarkBias] = assess(x_lm, 0.01);
  else out[effect::kLandmarkBias] = Identifiability{0.0, std::numeric_limits<double>::infinity(), 0.01};
  out[effect::kHeadingError] = assess(x_head, deg2rad(1.0));
  out[effect::kAngleOffset] = assess(x_angle, deg2rad(1.0));
  out[effect::kRangeDrift] = assess(x_drift, tmax > tmin ? 0.01 / (tmax - tmin) : 0.0);
  out[effect::kIncidenceBias] = assess(x_inc, 0.01);
  out[effect::kOdometryScale] = assess(x_scale, 0.01);
  // Variance-type effects: variety of the covariate beyond a constant (sigma_e).
  auto variety = [&](auto covariate, double ref) {
    double m = 0.0, m2 = 0.0;
    for (const auto& r : rs) {
      const double g = covariate(r.r);
      m += g / static_cast<double>(n);
      m2 += g * g / static_cast<double>(n);
    }
    Identifiability id;
    id.ratio = std::clamp((m2 - m * m) / (m2 + 1e-4), 0.0, 1.0);
    // sigma of the exponent: 1 / sqrt(2 n var(g)) (Fisher information of a log-sigma slope).
    const double v = std::max(m2 - m * m, 0.0);
    id.se = v > 0.0 ? 1.0 / std::sqrt(2.0 * static_cast<double>(n) * v) : std::numeric_limits<double>::infinity();
    id.ref = ref;
    return id;
  };
  out[effect::kIncidenceNoise] = variety([](const JointReading& r) { return -std::log(r.cos_incidence); }, 0.5);
  out[effect::kRangeNoiseLaw] =
      variety([&](const JointReading& r) { return std::log(std::max(fit.model.bias(r.d_m), 1e-3)); }, 0.5);
  std::size_t edges = 0;
  for (const auto& r : rs) edges += r.r.edge;
  const bool both = edges >= 10 && rs.size() - edges >= 10;
  out[effect::kMixedPixels] = Identifiability{both ? 1.0 : 0.0, both ? 0.0 : std::numeric_limits<double>::infinity(), 0.02};
  return out;
}

/// Standardised residuals (under a baseline refit) of simulated data, with their groups.
struct ZSample {
  std::vector<double> z;
  std::vector<long> group;
};

long groupKey(const JointReading& r) {
  return (static_cast<long>(r.landmark) * 100000 + static_cast<long>(r.stop)) * 2 + (r.edge ? 1 : 0);
}

Closeness closeness(const ZSample& measured, const ZSample& simulated) {
  Closeness c;
  c.ks_distance = ksDistance(measured.z, simulated.z);
  std::map<long, std::pair<std::vector<double>, std::vector<double>>> g;
  for (std::size_t i = 0; i < measured.z.size(); ++i) g[measured.group[i]].first.push_back(measured.z[i]);
  for (std::size_t i = 0; i < simulated.z.size(); ++i) g[simulated.group[i]].second.push_back(simulated.z[i]);
  auto var = [](const std::vector<double>& v) {
    double m = 0.0, s = 0.0;
    for (double x : v) m += x / static_cast<double>(v.size());
    for (double x : v) s += (x - m) * (x - m);
    return s / static_cast<double>(v.size() - 1);
  };
  std::vector<double> logs;
  for (const auto& [k, v] : g) {
    if (v.first.size() < 5 || v.second.size() < 5) continue;
    const double a = var(v.first), b = var(v.second);
    if (!(a > 0.0 && b > 0.0)) continue;
    logs.push_back(std::abs(std::log(a / b)));
  }
  c.groups = logs.size();
  if (!logs.empty()) {
    std::nth_element(logs.begin(), logs.begin() + static_cast<long>(logs.size() / 2), logs.end());
    c.variance_ratio_median_abs_log = logs[logs.size() / 2];
  }
  return c;
}

std::vector<ResidualRecord> records(const std::vector<Row>& rs) {
  std::vector<ResidualRecord> out;
  out.reserve(rs.size());
  for (const auto& w : rs) {
    ResidualRecord r;
    r.range_m = w.r.d_m;
    r.incidence_rad = std::acos(std::clamp(w.r.cos_incidence, 0.0, 1.0));
    r.lateral = w.r.lateral;
    r.group = w.r.landmark;
    r.time = static_cast<double>(w.r.scan);
    r.bearing_rad = w.r.angle_rad;
    r.stop = static_cast<int>(w.r.stop);
    r.edge = w.r.edge;
    r.residual_m = w.r.y_m - w.r.mean_m;
    r.z = w.z;
    out.push_back(r);
  }
  return out;
}

/// MSE ratio (seed 000 eq. 31) of a fitted model's correction of the readings against the truth:
/// the effect terms are taken off each reading, then f is inverted (LS).
double calibrationMseRatio(const LandmarkObservations& obs, const JointResult& fit, const JointConfig& cfg,
                           const std::vector<std::vector<double>>& truth) {
  RangeModel m = fit.model;
  m.range_min_m = obs.range_min_m;
  m.range_max_m = fit.window_max_m;
  std::optional<RangeInverter> inv;
  try {
    inv.emplace(m, inversionWindow(m, InversionMethod::ls));
  } catch (const std::invalid_argument&) {
    return kNaN;
  }
  const auto rd = evaluateJoint(obs, fit, cfg);
  std::vector<double> t, raw, cor;
  std::size_t k = 0;
  for (std::size_t si = 0; si < obs.sightings.size(); ++si) {
    const auto& s = obs.sightings[si];
    for (std::size_t j = 0; j < s.beams.size(); ++j) {
      if (!std::isfinite(s.beams[j].range_m)) continue;
      while (k < rd.size() && rd[k].sighting < si) ++k;
      if (k >= rd.size() || rd[k].sighting != si || si >= truth.size() || j >= truth[si].size()) continue;
      const JointReading& r = rd[k++];
      const double terms = r.mean_m - fit.model.bias(r.d_m);
      const auto d = inv->invert(r.y_m - terms);
      t.push_back(truth[si][j]);
      raw.push_back(r.y_m);
      cor.push_back(d ? *d : kNaN);
    }
  }
  return compareRanges(t, raw, cor).mse_ratio;
}

/// Size of a fitted effect in the unit of its identifiability standard error (RMS over components).
double effectSize(const std::string& e, const JointResult& f) {
  const auto& x = f.effects;
  if (e == effect::kLandmarkBias) {
    double s = 0.0;
    for (const auto& [id, o] : x.landmark_offset_m) s += o * o;
    return x.landmark_offset_m.empty() ? 0.0 : std::sqrt(s / static_cast<double>(x.landmark_offset_m.size()));
  }
  if (e == effect::kHeadingError) return x.heading_rms_rad;
  if (e == effect::kRangeDrift) return std::abs(x.drift_m_per_scan);
  if (e == effect::kAngleOffset) return std::abs(x.angle_offset_rad);
  if (e == effect::kIncidenceBias) return std::abs(x.incidence_bias_m);
  if (e == effect::kOdometryScale) return std::abs(x.odometry_scale);
  if (e == effect::kIncidenceNoise) return std::abs(x.incidence_noise_exponent);
  if (e == effect::kRangeNoiseLaw) return std::abs(x.noise_exponent - 2.0);
  return 0.0;
}

std::map<std::string, double> effectEstimates(const std::string& e, const JointResult& f) {
  const auto& x = f.effects;
  std::map<std::string, double> m;
  if (e == effect::kIncidenceNoise) m["incidence_noise_exponent"] = x.incidence_noise_exponent;
  if (e == effect::kIncidenceBias) m["incidence_bias_m"] = x.incidence_bias_m;
  if (e == effect::kLandmarkBias) {
    double s = 0.0;
    for (const auto& [id, o] : x.landmark_offset_m) {
      m["landmark_offset_m[" + std::to_string(id) + "]"] = o;
      s += o * o;
    }
    m["landmark_offset_rms_m"] = x.landmark_offset_m.empty() ? 0.0 : std::sqrt(s / static_cast<double>(x.landmark_offset_m.size()));
  }
  if (e == effect::kHeadingError) m["heading_rms_deg"] = rad2deg(x.heading_rms_rad);
  if (e == effect::kRangeDrift) m["range_drift_m_per_scan"] = x.drift_m_per_scan;
  if (e == effect::kMixedPixels) m["mixed_pixel_fraction"] = x.mixed_pixel_fraction;
  if (e == effect::kAngleOffset) m["angle_offset_deg"] = rad2deg(x.angle_offset_rad);
  if (e == effect::kRangeNoiseLaw) m["noise_exponent"] = x.noise_exponent;
  if (e == effect::kOdometryScale) m["odometry_scale"] = x.odometry_scale;
  return m;
}

std::map<std::string, double> sceneKeys(const std::string& e, const JointResult& f, const ReplicaPlan& plan) {
  std::map<std::string, double> k;
  const auto& x = f.effects;
  const auto& c = plan.config;
  for (std::size_t i = 0; i < c.model.bias.alpha.size(); ++i)
    k["sensor.bias_alpha[" + std::to_string(i) + "]"] = c.model.bias.alpha[i];
  if (c.model.noise.kind == NoiseKind::power) k["sensor.noise.exponent (kind power)"] = c.model.noise.exponent;
  k["sensor.noise.sigma_e"] = c.model.noise.sigma_e;
  if (e == effect::kIncidenceNoise) k["sensor.effects.incidence_noise_exponent"] = x.incidence_noise_exponent;
  if (e == effect::kIncidenceBias) k["sensor.effects.incidence_bias_m"] = x.incidence_bias_m;
  if (e == effect::kLandmarkBias)
    for (std::size_t i = 0; i < plan.ids.size(); ++i)
      k["landmarks[" + std::to_string(i) + "].range_offset_m (id " + std::to_string(plan.ids[i]) + ")"] =
          c.landmarks[i].range_offset_m;
  if (e == effect::kHeadingError) k["path.sigma_psi_deg"] = rad2deg(x.heading_rms_rad);
  if (e == effect::kRangeDrift) k["sensor.effects.range_drift_m_per_scan"] = x.drift_m_per_scan;
  if (e == effect::kMixedPixels) k["sensor.effects.mixed_pixel_fraction"] = x.mixed_pixel_fraction;
  if (e == effect::kAngleOffset) k["sensor.mount_yaw_deg"] = rad2deg(x.angle_offset_rad);
  if (e == effect::kOdometryScale) k["path.step_error_fraction"] = x.odometry_scale;
  return k;
}

}  // namespace

std::vector<std::string> sequenceCandidates() { return allCandidates(); }

DiagnosisResult diagnoseSequence(const LandmarkObservations& obs, const DiagnoseConfig& config,
                                 const std::vector<std::vector<double>>* true_range_m) {
  config.validate();
  DiagnosisResult out;
  out.mode = DiagnoseMode::sequence;
  out.seed = config.seed;
  out.replicas = config.replicas;
  out.folds = config.folds;
  std::vector<std::string> candidates = config.candidates.empty() ? allCandidates() : config.candidates;
  for (const auto& c : candidates)
    if (std::find(allCandidates().begin(), allCandidates().end(), c) == allCandidates().end())
      throw std::invalid_argument("diagnose: '" + c + "' is not a candidate effect for a sequence");
  {
    std::set<std::size_t> scans, stops;
    std::set<int> ids;
    for (const auto& s : obs.sightings) {
      scans.insert(s.scan);
      stops.insert(s.stop);
      ids.insert(s.landmark);
      out.readings += s.beams.size();
    }
    out.scans = scans.size();
    out.stops = stops.size();
    out.landmarks = ids.size();
  }

  // 1. Baseline: the seeds' model.
  CalibrationConfig cc;
  cc.method = Method::joint;
  cc.max_order = config.max_order;
  cc.joint.effects.estimate_heading = false;
  cc.joint.sigma_s_m = config.sigma_s_m;
  cc.triangulation.sigma_s_m = config.sigma_s_m;
  CalibrationModel cal;
  try {
    cal = calibrate(obs, cc);
  } catch (const std::invalid_argument& e) {
    cal.status = "calibration_failed";
    cal.message = e.what();
  }
  if (cal.status != "ok") {
    out.status = cal.status;
    out.message = "the baseline calibration failed: " + cal.message;
    return out;
  }
  JointConfig base;
  base.order = std::max(cal.model.bias.order(), 1);
  base.noise = NoiseKind::squared;
  base.sigma_s_m = cc.joint.sigma_s_m;
  base.sigma_psi_rad = deg2rad(2.0);  // prior of the heading_error model's per-stop headings
  base.estimate_radius = !obs.landmark_radius_m.has_value();
  base.keep_all_beams = true;
  base.reselect = false;
  base.covariance = false;
  base.outer_iterations = 4;
  base.outlier_floor = config.outlier_floor;
  base.effects.estimate_heading = false;
  base.cauchy_loss = true;
  // Fits that start from a converged solution (replicas, folds) skip the geometry pass and
  // re-estimate the noise law at most twice.
  auto warm = [](JointConfig c) {
    c.settle_geometry = false;
    c.outer_iterations = 2;
    c.max_solver_iterations = 200;
    return c;
  };
  // Two starts, the better fit kept (readings and odometry): the calibration's refined solution,
  // and a neutral one that no range effect has bent (landmarks triangulated from bearings
  // alone, commanded poses, the closed form's bias).
  JointInit init;
  init.poses = cal.stop_poses;
  init.model = cal.model;
  init.radius_m = landmarkRadius(obs);
  for (const auto& l : cal.landmarks)
    if (l.status == "ok") {
      init.centres[l.id] = Eigen::Vector2d(l.x_m, l.y_m);
      init.radius_m = l.radius_m;
    }
  std::optional<JointInit> neutral;
  int closed_form_order = base.order;
  {
    CalibrationConfig cf = cc;
    cf.method = Method::closed_form;
    const CalibrationModel m = calibrate(obs, cf);
    if (m.status == "ok") {
      JointInit n;
      n.poses = obs.commanded;
      n.radius_m = init.radius_m;
      for (const auto& l : m.landmarks)
        if (l.status == "ok") n.centres[l.id] = Eigen::Vector2d(l.x_m, l.y_m);
      n.model = m.model;
      closed_form_order = std::max(m.model.bias.order(), 1);
      if (n.centres.size() == init.centres.size()) neutral = n;
    }
  }
  auto total = [](const JointResult& r) {
    return r.poses.empty() ? std::numeric_limits<double>::infinity() : r.neg_log_likelihood + r.prior_neg_log_likelihood;
  };
  auto orderOf = [](JointInit i, int order) {
    i.model.bias.alpha.resize(static_cast<std::size_t>(order) + 1, 0.0);
    return i;
  };
  auto bestOf = [&](const JointInit& a, const JointConfig& cfg, bool both = true) {
    JointResult r = refineJoint(obs, orderOf(a, cfg.order), cfg);
    if (neutral && both) {
      JointResult other = refineJoint(obs, orderOf(*neutral, cfg.order), cfg);
      if (total(other) < total(r)) r = std::move(other);
    }
    return r;
  };
  // The order: the calibration's, or the closed form's when they differ and it fits better by AIC
  // (an effect the baseline lacks can drag the joint refinement to a wrong order).
  JointResult fit0 = bestOf(init, base);
  if (closed_form_order != base.order && neutral) {
    JointConfig other = base;
    other.order = closed_form_order;
    JointResult alt = bestOf(init, other);
    if (!alt.poses.empty() && 2.0 * (total(alt) - total(fit0)) + 2.0 * (other.order - base.order) < 0.0) {
      fit0 = std::move(alt);
      base = other;
    }
  }
  if (fit0.poses.empty()) {
    out.status = "baseline_failed";
    out.message = fit0.message;
    return out;
  }
  out.baseline = fit0.model;
  out.baseline.range_min_m = obs.range_min_m;
  out.baseline.range_max_m = obs.range_max_m;
  out.baseline_sigma_theta_rad = fit0.sigma_theta_rad;
  out.baseline_radius_m = fit0.radius_m;
  out.radius_known = obs.landmark_radius_m.has_value();
  out.baseline_neg_log_likelihood = fit0.neg_log_likelihood + fit0.prior_neg_log_likelihood;
  out.baseline_extra["pose_scatter_m"] = fit0.pose_scatter_m;
  out.baseline_extra["sigma_s_prior_m"] = base.sigma_s_m;
  out.baseline_extra["readings_used"] = static_cast<double>(fit0.readings);
  const std::vector<Row> measured_rows = rows(obs, fit0, base);
  const auto measured_stats = statistics(obs, fit0, measured_rows, base);
  out.measured = records(measured_rows);

  // 2. Parametric bootstrap from the fitted baseline.
  const ReplicaPlan plan0 = replicaPlan(obs, fit0, out.radius_known);
  std::map<std::string, std::vector<double>> replica_stats;
  ZSample sim_base;
  for (int b = 0; b < config.replicas; ++b) {
    const LandmarkObservations rep =
        simulateReplica(plan0, obs, poseNoise(fit0, base), deriveSeed(config.seed, 1000 + static_cast<std::uint64_t>(b)));
    const JointResult f = refineJoint(rep, initFrom(fit0), warm(base));
    if (f.poses.empty()) continue;
    const auto rr = rows(rep, f, base);
    for (const auto& [k, v] : statistics(rep, f, rr, base)) replica_stats[k].push_back(v);
    if (b < config.closeness_replicas)
      for (const auto& r : rr) {
        sim_base.z.push_back(r.z);
        sim_base.group.push_back(groupKey(r.r));
      }
    if (b == 0) out.simulated_baseline = records(rr);
  }
  out.battery = makeBattery(statInfo(), measured_stats, replica_stats);
  auto batteryOf = [&](const std::string& name) -> const Discrepancy* {
    for (const auto& d : out.battery)
      if (d.name == name) return &d;
    return nullptr;
  };

  // 3. Candidates: full fits, held-out likelihoods (folds by scan), identifiability.
  std::vector<JointConfig> cfgs;
  std::vector<JointResult> fits;
  // The path terms start from what the baseline's refined path shows (the baseline's optimum is
  // a stationary point of the extended models along them): its rotation and stretch against
  // the commanded path.
  const double path_info = [&] {
    double cx = 0.0, cy = 0.0, info = 0.0;
    for (const auto& c : obs.commanded) {
      cx += c.x_m / static_cast<double>(obs.commanded.size());
      cy += c.y_m / static_cast<double>(obs.commanded.size());
    }
    for (const auto& c : obs.commanded) info += (c.x_m - cx) * (c.x_m - cx) + (c.y_m - cy) * (c.y_m - cy);
    return info;
  }();
  const double sqrt_info = std::sqrt(std::max(path_info, 1e-12));
  for (const auto& e : candidates) {
    cfgs.push_back(effectConfig(base, e));
    JointInit start = initFrom(fit0);
    if (e == effect::kAngleOffset) {
      // Turn the baseline's world (which turned to absorb the offset) back onto the commanded
      // path, and let the beams turn instead.
      const double turn = -measured_stats.at("path_rotation") * base.sigma_s_m / sqrt_info;
      double cx = 0.0, cy = 0.0;
      for (const auto& c : obs.commanded) {
        cx += c.x_m / static_cast<double>(obs.commanded.size());
        cy += c.y_m / static_cast<double>(obs.commanded.size());
      }
      const double ct = std::cos(turn), st = std::sin(turn);
      auto rotate = [&](double& x, double& y) {
        const double dx = x - cx, dy = y - cy;
        x = cx + ct * dx - st * dy;
        y = cy + st * dx + ct * dy;
      };
      for (auto& p : start.poses) rotate(p.x_m, p.y_m);
      for (auto& [id, c] : start.centres) rotate(c.x(), c.y());
      start.effects.angle_offset_rad = turn;
    }
    if (e == effect::kOdometryScale) start.effects.odometry_scale = measured_stats.at("path_scale") * base.sigma_s_m / sqrt_info;
    // The neutral start matters for the terms that bend the geometry the baseline settled in.
    fits.push_back(bestOf(start, cfgs.back(), e == effect::kIncidenceBias || e == effect::kLandmarkBias));
  }
  const std::vector<int> fold = folds(obs, config.folds);
  std::vector<double> ll_base;                               // per held-out reading
  std::vector<std::vector<double>> ll_cand(candidates.size());
  std::vector<std::size_t> block;                             // scan of each held-out reading
  for (int f = 0; f < config.folds; ++f) {
    std::vector<bool> train(obs.sightings.size()), test(obs.sightings.size());
    bool any = false;
    for (std::size_t i = 0; i < obs.sightings.size(); ++i) {
      train[i] = fold[i] != f;
      test[i] = fold[i] == f;
      any = any || test[i];
    }
    if (!any) continue;
    const LandmarkObservations tr = subset(obs, train), te = subset(obs, test);
    const JointResult fb = refineJoint(tr, initFrom(fit0), warm(base));
    if (fb.poses.empty()) continue;
    const auto eb = evaluateJoint(te, fb, base);
    std::vector<std::vector<JointReading>> ec(candidates.size());
    bool ok = true;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const JointResult fc = refineJoint(tr, fits[c].poses.empty() ? initFrom(fit0) : initFrom(fits[c]), warm(cfgs[c]));
      if (fc.poses.empty()) {
        ok = false;
        break;
      }
      ec[c] = evaluateJoint(te, fc, cfgs[c]);
      if (ec[c].size() != eb.size()) ok = false;
    }
    if (!ok) continue;
    for (std::size_t i = 0; i < eb.size(); ++i) {
      ll_base.push_back(eb[i].log_likelihood);
      block.push_back(eb[i].scan);
      for (std::size_t c = 0; c < candidates.size(); ++c) ll_cand[c].push_back(ec[c][i].log_likelihood);
    }
  }
  // Odometry, leave one stop out (full-data fits).
  {
    const auto ob = odometryHeldOut(obs, fit0, base);
    std::vector<std::vector<double>> oc(candidates.size());
    for (std::size_t c = 0; c < candidates.size(); ++c)
      oc[c] = fits[c].poses.empty() ? std::vector<double>(ob.size(), kNaN) : odometryHeldOut(obs, fits[c], cfgs[c]);
    for (std::size_t k = 0; k < ob.size() && !ll_base.empty(); ++k) {
      // One block per stop, after the scans' blocks; two observations (x, y) per stop.
      const std::size_t key = std::numeric_limits<std::size_t>::max() - k;
      for (int twice = 0; twice < 2; ++twice) {
        ll_base.push_back(0.5 * ob[k]);
        block.push_back(key);
        for (std::size_t c = 0; c < candidates.size(); ++c) ll_cand[c].push_back(0.5 * oc[c][k]);
      }
    }
  }
  if (ll_base.empty()) {
    out.status = "cross_validation_failed";
    out.message = "no fold could be fitted: too few scans or landmarks";
    return out;
  }
  const double n_heldout = static_cast<double>(ll_base.size());
  {
    double s = 0.0;
    for (double v : ll_base) s += v;
    out.baseline_heldout_nats_per_point = s / n_heldout;
  }
  const auto ident = identifiability(obs, fit0, measured_rows, base);
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    CandidateResult r;
    r.effect = candidates[c];
    r.statistic = statisticOf(r.effect);
    if (const Discrepancy* d = batteryOf(r.statistic)) {
      r.score_p_value = d->p_value;
      r.effect_size = d->effect_size;
    }
    const JointResult& fc = fits[c];
    if (fc.poses.empty()) {
      r.applicable = false;
      r.note = "the extended fit failed: " + fc.message;
      r.p_value = kNaN;
      out.candidates.push_back(r);
      continue;
    }
    // Held-out gain per point, standard error from per-scan blocks.
    std::map<std::size_t, double> per_scan;
    double sum = 0.0;
    for (std::size_t i = 0; i < ll_base.size(); ++i) {
      const double diff = ll_cand[c][i] - ll_base[i];
      sum += diff;
      per_scan[block[i]] += diff;
    }
    r.heldout_gain_nats_per_point = sum / n_heldout;
    double ss = 0.0;
    const double mean_block = sum / static_cast<double>(per_scan.size());
    for (const auto& [scan, v] : per_scan) ss += (v - mean_block) * (v - mean_block);
    const double nb = static_cast<double>(per_scan.size());
    r.heldout_gain_se = nb > 1 ? std::sqrt(ss / (nb - 1.0) * nb) / n_heldout : 0.0;
    r.p_heldout = heldoutPValue(r.heldout_gain_nats_per_point, r.heldout_gain_se);
    r.parameters = fc.effect_parameters;
    const double lr = 2.0 * (fit0.neg_log_likelihood + fit0.prior_neg_log_likelihood - fc.neg_log_likelihood -
                             fc.prior_neg_log_likelihood);
    r.delta_aic = 2.0 * r.parameters - lr;
    // In-sample evidence too, for one-parameter effects: where the baseline's parameters absorb
    // most of an effect (a constant bearing rotation moves the poles) the held-out gain is small
    // while the likelihood ratio on all the data is not. Naming still needs a positive held-out gain.
    r.p_likelihood_ratio = likelihoodRatioPValue(lr, r.parameters);
    r.p_value = combinedPValue(r.p_heldout, r.score_p_value, r.p_likelihood_ratio);
    if (const auto it = ident.find(r.effect); it != ident.end()) {
      r.information_ratio = it->second.ratio;
      r.standard_error = it->second.se;
      // Estimable at the smallest size worth naming, or the estimate stands 4 standard errors
      // clear of zero once the baseline's parameters are free.
      r.identifiable = it->second.se < std::max(it->second.ref, effectSize(r.effect, fc) / 4.0);
    }
    if (!r.identifiable) {
      if (r.effect == effect::kIncidenceBias && !out.radius_known)
        r.note = "confounded with the landmark radius and alpha_0 (radius estimated; give landmark_radius_m)";
      else if (r.effect == effect::kOdometryScale && !out.radius_known)
        r.note = "a step-length error is a change of the world's scale, which the bias polynomial absorbs when the radius is unknown";
      else if (r.effect == effect::kMixedPixels) r.note = "too few outermost or inner beams";
      else r.note = "the baseline's parameters absorb it (standard error " + std::to_string(r.standard_error) + " after them)";
    }
    r.estimates = effectEstimates(r.effect, fc);
    if (true_range_m) r.calibration_mse_ratio = calibrationMseRatio(obs, fc, cfgs[c], *true_range_m);
    out.candidates.push_back(r);
  }
  if (true_range_m) out.calibration_mse_ratio_baseline = calibrationMseRatio(obs, fit0, base, *true_range_m);

  // 4. The cause. An angle offset is one heading shared by all stops (nested), handled by parsimony.
  out.primary_cause = nameCause(out.candidates, config.alpha, out.decision, {{effect::kAngleOffset, effect::kHeadingError}});

  // 5. The extended model and how close its simulation comes to the data.
  ZSample measured_z;
  for (const auto& r : measured_rows) {
    measured_z.z.push_back(r.z);
    measured_z.group.push_back(groupKey(r.r));
  }
  out.closeness_baseline = closeness(measured_z, sim_base);
  const auto named = std::find(candidates.begin(), candidates.end(), out.primary_cause);
  if (named != candidates.end()) {
    const std::size_t c = static_cast<std::size_t>(named - candidates.begin());
    const JointResult& fc = fits[c];
    const CandidateResult& r = out.candidates[c];
    out.extended_parameters = r.estimates;
    out.extended_bias_alpha = fc.model.bias.alpha;
    out.gain_heldout_nats_per_point = r.heldout_gain_nats_per_point;
    out.gain_delta_aic = r.delta_aic;
    out.calibration_mse_ratio_extended = r.calibration_mse_ratio;
    const ReplicaPlan plan = replicaPlan(obs, fc, out.radius_known);
    out.scene_keys = sceneKeys(out.primary_cause, fc, plan);
    ZSample sim_ext;
    for (int b = 0; b < config.closeness_replicas; ++b) {
      const LandmarkObservations rep = simulateReplica(plan, obs, poseNoise(fc, cfgs[c]),
                                                       deriveSeed(config.seed, 5000 + static_cast<std::uint64_t>(b)));
      const JointResult f = refineJoint(rep, initFrom(fit0), warm(base));
      if (f.poses.empty()) continue;
      const auto rr = rows(rep, f, base);
      for (const auto& w : rr) {
        sim_ext.z.push_back(w.z);
        sim_ext.group.push_back(groupKey(w.r));
      }
      if (out.simulated_extended.empty()) out.simulated_extended = records(rr);
    }
    out.closeness_extended = closeness(measured_z, sim_ext);
  }
  return out;
}

}  // namespace lidarcal::diagnosis
