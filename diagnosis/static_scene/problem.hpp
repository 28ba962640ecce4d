// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The static diagnosis' problem object (diagnosis/skeleton.hpp's five steps on the bin, wall and
// tail models). Internal to the diagnosis library.

#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "diagnosis/battery.hpp"
#include "diagnosis/held_out.hpp"
#include "diagnosis/skeleton.hpp"
#include "diagnosis/static_scene/replicas.hpp"
#include "diagnosis/static_scene/tail_study.hpp"
#include "diagnosis/static_scene/wall_model.hpp"

namespace lidarcal::diagnosis::static_scene {

/// Repeated scans from one pose, diagnosed with the bin and wall models: the DiagnosisMode of
/// runDiagnosis (diagnosis/skeleton.hpp), its steps in the order they run. Its methods live in
/// baseline.cpp (steps 1-2), candidates.cpp and tail_attribution.cpp (step 3), verdict.cpp (step 4)
/// and extended_model.cpp (step 5).
class StaticDiagnosis final : public DiagnosisMode {
 public:
  StaticDiagnosis(const StaticScans& data, const DiagnoseConfig& config,
                  const std::vector<Effect>& candidates, std::vector<WallLine>* walls_out)
      : data_(data), config_(config), candidates_(candidates), walls_out_(walls_out) {}
  StaticDiagnosis(const StaticDiagnosis&) = delete;  // scored_readings_ points into the object
  StaticDiagnosis& operator=(const StaticDiagnosis&) = delete;

  bool fitBaseline(DiagnosisResult& out) override;
  std::map<std::string, double> measuredStatistics(DiagnosisResult& out) override;
  void replica(int b, std::map<std::string, std::vector<double>>& stats,
               DiagnosisResult& out) override;
  const std::vector<StatisticInfo>& statisticInfo() const override {
    return diagnosis::statisticInfo(DiagnoseMode::static_scene);
  }
  void heldOut(HeldOut& held) override;
  const char* noHeldOut() const override { return "no held-out reading"; }
  void beforeCandidates(DiagnosisResult& out) override;
  CandidateResult candidate(std::size_t c, const HeldOut& held,
                            const DiagnosisResult& out) override;
  void afterCandidates(DiagnosisResult& out) override;
  std::vector<std::pair<Effect, Effect>> nestedEffects() const override { return {}; }
  void refineCause(DiagnosisResult& out) override;
  void refineCauseByTails(DiagnosisResult& out);
  double darkRangeCorrelation() const;
  bool reRankUnderTails(DiagnosisResult& out);
  Closeness closenessBaseline(const DiagnosisResult& out) const override {
    return closenessOf(out.measured, baseline_replicas_);
  }
  void extend(std::size_t c, DiagnosisResult& out) const override;

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
  void tailClasses(TailAttribution& ta, const TailModel& full,
                   const std::vector<TailReading>& all) const;
  void tailRobust(DiagnosisResult& out, const std::vector<TailReading>& all,
                  const TailModel& pooled);
  double inSampleLogLikelihood(const FreeTerms& fl, ReadingModel* fitted) const;
  bool notApplicable(CandidateResult& r) const;
  void setIdentifiability(CandidateResult& r) const;
  void setEstimates(CandidateResult& r, const ReadingModel& fm) const;
  void setSceneKeys(DiagnosisResult& out, double a0, const ReadingModel& sim_model,
                    const RangeEffects& fx) const;
  Closeness closenessOf(const std::vector<ResidualRecord>& measured, const SimSample& sim) const;

  const StaticScans& data_;
  const DiagnoseConfig& config_;
  const std::vector<Effect>& candidates_;
  std::vector<WallLine>* walls_out_;
  std::size_t window_scans_ = 0;  // scans per window (0: one pose)
  BinnedReadings binned_;         // readings in direction bins
  std::vector<BinFit> bin_fits_;  // the baseline's bin locations
  ReadingModel baseline_model_;   // the baseline's reading model
  std::vector<Line> wall_lines_;  // wall lines found in the bin means
  double fixed_alpha0_ = kNaN;    // alpha_0 held (NaN: from the walls' straightness)
  bool alpha0_identified_ = false;
  WallFit walls_, walls_with_bias_;  // the wall model without and with the incidence bias
  double reading_grid_m_ = 0.0;      // reading grid (0: none)
  BinnedReadings dequantised_;       // binned_ spread over its grid cells (reading_grid_m_ > 0)
  // the readings every likelihood is scored on (binned_ or dequantised_)
  const BinnedReadings* scored_readings_ = &binned_;
  std::size_t edge_bins_ = 0;             // bins at depth discontinuities
  SimSample baseline_replicas_;           // baseline replicas (closeness)
  std::vector<FreeTerms> free_terms_;     // per candidate
  double baseline_in_sample_ll_ = 0.0;    // in-sample log-likelihood of the baseline
  std::vector<ReadingModel> fit_on_all_;  // per candidate: fitted on all the data
  bool tail_study_on_ = false;            // the tail study runs (heavy_tails is a candidate)
  TailStudy tail_study_;                  // the tail models and their held-out log-likelihoods
  // effect -> its parameter fitted under the pooled contamination
  std::map<Effect, double> robust_estimate_;
  std::map<Effect, double> robust_sigma_e_;  // effect -> the core's sigma_e fitted with it
  bool named_by_tails_ = false;              // the cause was named from the tails' covariates
};

}  // namespace lidarcal::diagnosis::static_scene
