// SPDX-License-Identifier: BSD-3-Clause
// Steps 1 and 2 of a static diagnosis: the readings binned (one pose, or windows when the sensor
// moved), the baseline's bin locations, noise law and wall model, the measured statistics, and
// the bootstrap replicas refitted from it.

#include <cmath>
#include <cstdio>

#include "common/plural.hpp"
#include "common/pose2.hpp"
#include "common/rng.hpp"
#include "diagnosis/static_scene/problem.hpp"
#include "diagnosis/static_scene/scene_changes.hpp"
#include "diagnosis/static_scene/statistics.hpp"

namespace lidarcal::diagnosis::static_scene {
namespace {

/// Least beam sector the wall lines must cover (summed over lines) for a static diagnosis: more
/// than a single target fills, less than the sparsest real room (docs/results/static-diagnosis.md).
constexpr double kMinWallSectorRad = deg2rad(10.0);

}  // namespace

bool StaticDiagnosis::fitBaseline(DiagnosisResult& out) {
  if (!makeData(out)) return false;
  // 1. Baseline: bin locations, the squared noise law, the wall model with alpha_0.
  fitWallModel();
  if (std::isfinite(config_.static_range_offset_m))
    out.baseline_extra["alpha0_given_m"] = fixed_alpha0_;
  std::vector<double> used_y;
  for (std::size_t i = 0; i < binned_.y.size(); ++i)
    if (binned_.bin_of[i] >= 0) used_y.push_back(binned_.y[i]);
  reading_grid_m_ = detectReadingGrid(used_y);
  if (reading_grid_m_ > 0.0) {
    dequantised_ = dequantised(binned_, reading_grid_m_, deriveSeed(config_.seed, 0xDE0A7ULL));
    scored_readings_ = &dequantised_;
  }
  for (const auto& b : binned_.bins) edge_bins_ += b.edge;
  describeBaseline(out);
  if (walls_out_) reportWalls();
  // The noise is read against range and incidence off the walls: straight surfaces seen over a
  // narrow sector (one target, such as the retro-reflector a range sweep was masked to) hold
  // neither spread, and any effect named from them would be chance.
  if (const double span = wallSector(); span < kMinWallSectorRad) {
    out.status.code = StatusCode::too_few_walls;
    char buf[320];
    std::snprintf(
        buf, sizeof buf,
        "the returns lie on %s seen over %.1f degrees (at least %.0f needed): record the "
        "repeated scans in a room with walls in view at several distances, not one target alone",
        plural(wall_lines_.size(), "straight surface").c_str(), rad2deg(span),
        rad2deg(kMinWallSectorRad));
    out.status.message = buf;
    return false;
  }
  return true;
}

/// The first and last beam angle of each wall line, over the bins the wall model fits
/// (+inf, -inf for a line without any).
std::vector<std::pair<double, double>> StaticDiagnosis::lineExtents() const {
  std::vector<std::pair<double, double>> ext(wall_lines_.size(), {kInf, -kInf});
  for (std::size_t bi : walls_.bins) {
    const Bin& b = binned_.bins[bi];
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
    out.status.message = "a static recording needs at least " + std::to_string(2 * config_.folds) +
                         " scans from the same pose";
    return false;
  }
  window_scans_ = config_.static_window > 0 ? static_cast<std::size_t>(config_.static_window) : 0;
  binned_ = makeBins(data_, window_scans_);
  if (config_.static_window == 0) {
    const double moved = movedFraction(binned_);
    out.baseline_extra["beams_moved_fraction"] = moved;
    if (moved > 0.3) {
      window_scans_ = 8;
      binned_ = makeBins(data_, window_scans_);
    }
  }
  out.baseline_extra["window_scans"] = static_cast<double>(window_scans_);
  // One pose: beams that saw objects move (a person, a reflector carried away) are left out;
  // the sensor's model is about the scene standing still.
  if (window_scans_ == 0)
    out.baseline_extra["scene_changed_bins"] = static_cast<double>(dropChangedBins(binned_));
  if (binned_.bins.size() < 10) {
    out.status.code = StatusCode::too_few_beams;
    out.status.message = "fewer than 10 beam directions return in enough scans";
    return false;
  }
  return true;
}

void StaticDiagnosis::fitWallModel() {
  baseline_model_ = fitModel(binned_, {}, FreeTerms{}, 0.0, bin_fits_);
  wall_lines_ = findWallLines(binned_, bin_fits_);
  fixed_alpha0_ = config_.static_range_offset_m;  // NaN: from the walls' straightness
  walls_ = fitWalls(binned_, bin_fits_, wall_lines_, false, fixed_alpha0_);
  // Walls too few or too short to bend measurably: alpha_0 stays unknown (held at 0).
  alpha0_identified_ = std::isfinite(fixed_alpha0_) || (walls_.ok && walls_.alpha0_se <= 0.05);
  if (!alpha0_identified_) {
    fixed_alpha0_ = 0.0;
    walls_ = fitWalls(binned_, bin_fits_, wall_lines_, false, fixed_alpha0_);
  }
  walls_with_bias_ = fitWalls(binned_, bin_fits_, wall_lines_, true, fixed_alpha0_);
}

void StaticDiagnosis::describeBaseline(DiagnosisResult& out) const {
  out.landmarks = wall_lines_.size();
  out.baseline.bias.alpha = {walls_.ok ? walls_.alpha0 : 0.0, 1.0};
  out.baseline.noise.kind = NoiseKind::squared;
  out.baseline.noise.sigma_e = baseline_model_.sigma_e;
  out.baseline.range_min_m = data_.range_min_m;
  out.baseline.range_max_m = data_.range_max_m;
  auto& extra = out.baseline_extra;
  extra["beam_bins"] = static_cast<double>(binned_.bins.size());
  extra["wall_lines"] = static_cast<double>(wall_lines_.size());
  extra["wall_bins"] = static_cast<double>(walls_.bins.size());
  extra["alpha0_m"] = walls_.ok && alpha0_identified_ ? walls_.alpha0 : kNaN;
  extra["alpha0_se_m"] =
      walls_.ok && alpha0_identified_ && !std::isfinite(config_.static_range_offset_m)
          ? walls_.alpha0_se
          : kNaN;
  extra["wall_roughness_m"] = walls_.ok ? walls_.tau : kNaN;
  extra["reading_grid_m"] = reading_grid_m_;
  extra["edge_bins"] = static_cast<double>(edge_bins_);
}

/// The fitted wall lines, for the caller (the geometric reference).
void StaticDiagnosis::reportWalls() const {
  walls_out_->clear();
  const auto extents = lineExtents();
  for (std::size_t l = 0; l < wall_lines_.size(); ++l) {
    WallLine wl;
    const Line& line = walls_.ok ? walls_.lines[l] : wall_lines_[l];
    wl.normal_rad = wrapAngle(line.theta);
    wl.distance_m = line.p;
    // Residuals exist only when the wall model's fit ran to its end (fitWalls returns early on
    // too few bins or a failed step).
    const bool fitted = walls_.resid.size() == walls_.bins.size();
    double ss = 0.0;
    for (std::size_t k = 0; k < walls_.bins.size(); ++k) {
      if (binned_.bins[walls_.bins[k]].wall != static_cast<int>(l)) continue;
      ++wl.bins;
      if (fitted) ss += walls_.resid[k] * walls_.resid[k];
    }
    wl.first_angle_rad = extents[l].first;
    wl.last_angle_rad = extents[l].second;
    wl.rms_m = !wl.bins ? 0.0 : fitted ? std::sqrt(ss / static_cast<double>(wl.bins)) : kNaN;
    walls_out_->push_back(wl);
  }
}

std::map<std::string, double> StaticDiagnosis::measuredStatistics(DiagnosisResult& out) {
  const auto measured_stats = staticStatistics(binned_, bin_fits_, baseline_model_, walls_,
                                               walls_with_bias_, reading_grid_m_);
  out.measured = residualRecordsOf(binned_, bin_fits_, baseline_model_);
  baseline_replicas_.var.resize(binned_.bins.size());
  return measured_stats;
}

/// One bootstrap replica: simulated from the fitted baseline, refitted from it.
void StaticDiagnosis::replica(int b, std::map<std::string, std::vector<double>>& stats,
                              DiagnosisResult& out) {
  const BinnedReadings rep = simulateStatic(
      binned_, bin_fits_, walls_, baseline_model_,
      deriveSeed(config_.seed, 2000 + static_cast<std::uint64_t>(b)), RangeEffects{});
  std::vector<BinFit> fr;
  const ReadingModel mr = fitModel(rep, {}, FreeTerms{}, 0.0, fr);
  const WallFit wr0 =
      fitWalls(rep, fr, walls_.ok ? walls_.lines : wall_lines_, false, fixed_alpha0_);
  const WallFit wrb =
      fitWalls(rep, fr, walls_.ok ? walls_.lines : wall_lines_, true, fixed_alpha0_);
  for (const auto& [k, v] : staticStatistics(rep, fr, mr, wr0, wrb, reading_grid_m_))
    stats[k].push_back(v);
  if (b >= config_.closeness_replicas && b != 0) return;
  const auto rec = residualRecordsOf(rep, fr, mr);
  if (b < config_.closeness_replicas) baseline_replicas_.add(rec, fr);
  if (b == 0) out.simulated_baseline = rec;
}

}  // namespace lidarcal::diagnosis::static_scene
