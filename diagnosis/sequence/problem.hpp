// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The sequence diagnosis' problem object (diagnosis/skeleton.hpp's five steps on joint
// refinements). Internal to the diagnosis library.

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "diagnosis/battery.hpp"
#include "diagnosis/held_out.hpp"
#include "diagnosis/sequence/extended_model.hpp"
#include "diagnosis/sequence/identifiability.hpp"
#include "diagnosis/sequence/odometry_noise.hpp"
#include "diagnosis/sequence/refits.hpp"
#include "diagnosis/sequence/replicas.hpp"
#include "diagnosis/sequence/statistics.hpp"
#include "diagnosis/skeleton.hpp"

namespace lidarcal::diagnosis::sequence {

/// A scan sequence with landmarks, diagnosed with joint refinements: the DiagnosisMode of
/// runDiagnosis (diagnosis/skeleton.hpp), its steps in the order they run. Its methods live in
/// baseline.cpp (step 1-2), candidate_fits.cpp and candidate_result.cpp (step 3), verdict.cpp
/// (step 4), extended_model.cpp (step 5), starts.cpp, noise_shape.cpp and odometry_noise.cpp.
class SequenceDiagnosis final : public DiagnosisMode {
 public:
  SequenceDiagnosis(const LandmarkObservations& obs, const DiagnoseConfig& config,
                    const std::vector<Effect>& candidates,
                    const std::vector<std::vector<double>>* truth)
      : obs_(obs), config_(config), candidates_(candidates), truth_(truth) {}

  bool fitBaseline(DiagnosisResult& out) override;
  std::map<std::string, double> measuredStatistics(DiagnosisResult& out) override;
  void replica(int b, std::map<std::string, std::vector<double>>& stats,
               DiagnosisResult& out) override;
  const std::vector<StatisticInfo>& statisticInfo() const override {
    return diagnosis::statisticInfo(DiagnoseMode::sequence);
  }
  void heldOut(HeldOut& held) override;
  const char* noHeldOut() const override {
    return "no fold could be fitted: too few scans or landmarks";
  }
  void beforeCandidates(DiagnosisResult&) override {
    identifiability_ = identifiability(obs_, baseline_fit_, measured_rows_, baseline_cfg_);
  }
  CandidateResult candidate(std::size_t c, const HeldOut& held,
                            const DiagnosisResult& out) override;
  void afterCandidates(DiagnosisResult& out) override;
  /// An angle offset is one heading shared by all stops (nested), handled by parsimony.
  std::vector<std::pair<Effect, Effect>> nestedEffects() const override {
    return {{Effect::angle_offset, Effect::heading_error}};
  }
  void refineCause(DiagnosisResult& out) override;
  void nameCauseBesideSymptom(DiagnosisResult& out, Effect symptom) const;
  bool ratioCountsBeside(std::size_t under, bool grid) const;
  void describeCauseBesideSymptom(DiagnosisResult& out, bool grid, std::size_t under,
                                  std::size_t tried, std::size_t best, double best_gain) const;
  void requireNoiseTermToHoldBesidePath(DiagnosisResult& out) const;
  std::vector<HeldOutGain> heldOutGainsBesideTerm(const std::vector<std::size_t>& effects,
                                                  std::size_t under, std::vector<JointResult>& full,
                                                  bool from_under = false) const;
  std::pair<JointConfig, JointInit> configWithBothTerms(std::size_t c, std::size_t under) const;
  double likelihoodRatioPBesideTerm(const JointResult& both, std::size_t under) const;
  Closeness closenessBaseline(const DiagnosisResult&) const override {
    return closeness(measured_z_, baseline_replica_z_);
  }
  void extend(std::size_t c, DiagnosisResult& out) const override;

 private:
  bool calibrateBaseline(DiagnosisResult& out);
  void findStarts();
  JointResult bestOf(const JointInit& start, const JointConfig& cfg, bool both = true) const;
  JointResult fitInTwoSteps(const LandmarkObservations& obs, const JointInit& start,
                            const JointConfig& cfg) const;
  JointResult replicaFit(const LandmarkObservations& rep) const;
  void chooseOrder();
  void fitOdometryNoise();
  void describeBaseline(DiagnosisResult& out) const;
  JointInit candidateStart(Effect e) const;
  /// The terms of the path (the odometry steps' frame and length): their evidence on a
  /// continuous recording is in the steps (stepHeldOut, and the likelihood ratio).
  static bool pathTerm(Effect e) {
    return e == Effect::angle_offset || e == Effect::odometry_scale;
  }
  /// The terms that move the fitted geometry (poses, landmarks) rather than shape the noise.
  static bool geometryTerm(Effect e) {
    return pathTerm(e) || e == Effect::incidence_bias || e == Effect::landmark_bias ||
           e == Effect::range_drift;
  }
  JointInit driveStart(Effect e, const JointResult& from) const;
  JointInit baselineStart(const JointResult& from) const;
  void fitCandidates(bool measured_start, const char* stage, std::size_t steps);
  std::optional<JointResult> sameOptimum(const LandmarkObservations& obs, std::size_t c,
                                         JointResult& fc, const JointResult& base) const;
  void applyCandidateGates(CandidateResult& r, const JointResult& fc, double lr) const;
  void setPValue(CandidateResult& r, std::size_t c, double lr) const;
  JointResult withCorrectedShape(const LandmarkObservations& obs, Effect e, const JointResult& base,
                                 const JointConfig& base_cfg, JointResult fc,
                                 const JointConfig& fc_cfg, double* statistic = nullptr) const;
  bool settleBaseline();
  void foldLikelihoods(HeldOut& held, std::size_t steps_before, std::size_t steps) const;
  LandmarkObservations dequantisedTestFold(const std::vector<int>& fold, int f) const;
  const LandmarkObservations& scoredReadings(const JointConfig& cfg,
                                             const LandmarkObservations& recorded,
                                             const LandmarkObservations& spread) const;
  void odometryLikelihoods(HeldOut& held) const;
  /// An effect the baseline already holds (heading_error under the motion prior, where the
  /// baseline refines the headings): its "extended" fits are the baseline's, not fitted again.
  bool inBaseline(Effect e) const {
    return e == Effect::heading_error && baseline_cfg_.effects.estimate_heading;
  }
  /// Student-t noise is not tested on a continuous recording: a held-out reading's predictive
  /// distribution under its pose's uncertainty is a scale mixture, wider-tailed than the Gaussian
  /// it is scored with, so clean drives would gain from a t (docs/results/hidden-effects.md,
  /// Robots that never stop).
  bool untested(Effect e) const {
    return e == Effect::heavy_tails && baseline_cfg_.effects.estimate_heading;
  }
  /// The rounded model where the readings lie on no grid: the baseline's.
  bool offGrid(Effect e) const { return e == Effect::quantisation && reading_grid_m_ <= 0.0; }
  /// The dark-surface model where no reading records an intensity (or all record one value): the
  /// baseline's.
  bool noIntensity(Effect e) const { return e == Effect::dark_surface && !intensity_varies_; }
  bool notFitted(Effect e) const { return whyNotFitted(e) != nullptr; }
  /// Why the candidate is not fitted (its note), or nullptr when it is.
  const char* whyNotFitted(Effect e) const {
    if (untested(e))
      return "not tested on a continuous recording: the held-out readings' pose uncertainty gives "
             "their predictive "
             "distribution tails of its own (clean simulated drives were named heavy_tails)";
    if (inBaseline(e))
      return "the baseline already refines every heading (a continuous recording: under the motion "
             "prior)";
    if (offGrid(e)) return "the readings lie on no grid of 0.1 to 20 mm";
    if (noIntensity(e))
      return "no reading records a return intensity (or all record one value): record with the "
             "driver's intensities on "
             "(ROS LaserScan intensities, a PCD intensity field)";
    return nullptr;
  }
  void setIdentifiability(CandidateResult& r, const JointResult& fc, bool radius_known) const;

  const LandmarkObservations& obs_;
  const DiagnoseConfig& config_;
  const std::vector<Effect>& candidates_;
  const std::vector<std::vector<double>>* truth_;  // true ranges, aligned with the beams (optional)
  CalibrationConfig calibration_cfg_;              // the calibration that starts the baseline
  CalibrationModel calibration_;
  JointConfig baseline_cfg_;                // the baseline's refinement
  JointInit calibrated_start_;              // start: the calibration's refined solution
  std::optional<JointInit> neutral_start_;  // start that no range effect has bent (when available)
  int closed_form_order_ = 1;
  JointResult baseline_fit_;  // the baseline fit
  std::vector<ReadingRow> measured_rows_;
  std::map<std::string, double> measured_stats_;
  ZSample measured_z_;
  ReplicaPlan baseline_plan_;                // replicas of the baseline
  ZSample baseline_replica_z_;               // residuals of the first replicas (closeness)
  std::vector<JointConfig> candidate_cfgs_;  // per candidate: its refinement
  std::vector<JointResult> candidate_fits_;  // per candidate: fit on all the data
  bool baseline_settled_ = false;  // a candidate's solution gave the baseline a better optimum
  // per candidate: the baseline's -log L in its optimum (heldOut)
  std::vector<double> baseline_nll_in_optimum_;
  // per candidate: its noise exponent's restricted likelihood ratio (NaN: none)
  std::vector<double> shape_lr_statistic_;
  // per geometry term (motion prior): the baseline refitted from its solution
  std::vector<JointResult> paired_baselines_;
  std::map<Effect, Identifiability> identifiability_;
  double reading_grid_m_ = 0.0;  // grid the readings lie on (0: none)
  // the motion prior's factors on the defaults (fitOdometryNoise)
  OdometryNoiseFactors odometry_noise_;
  bool intensity_varies_ = false;     // the readings record at least two different intensities
  LandmarkObservations dequantised_;  // obs_ spread over its grid cells (reading_grid_m_ > 0)
};

}  // namespace lidarcal::diagnosis::sequence
