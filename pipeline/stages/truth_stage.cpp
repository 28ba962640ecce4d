// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/truth_stage.hpp"

#include <string>

#include "calibration/calibrate.hpp"
#include "calibration/truth_evaluation.hpp"
#include "pipeline/reports/model_text.hpp"
#include "pipeline/reports/papers.hpp"

namespace lidarcal::pipeline {

std::vector<ComparedModel> compareWithTruth(const io::Sequence& seq,
                                            const std::filesystem::path& corrected_dir,
                                            const io::SimulationTruth& truth,
                                            const SequenceCalibration& cal,
                                            const calibration::CalibrationConfig& config,
                                            const SequenceCorrection& how) {
  using calibration::evaluate;
  const calibration::InversionMethod method = how.method;
  const calibration::Outside outside = how.outside;
  std::vector<ComparedModel> compared;
  compared.push_back({"lidarcal " + cal.model.method + " (no ground truth), the written scans",
                      cal.model, evaluate(io::openSequence(corrected_dir), seq, truth)});
  if (cal.model.method != "closed-form") {
    auto cf_config = config;
    cf_config.method = calibration::Method::closed_form;
    const CalibrationModel cf = calibration::calibrate(cal.observations, cf_config);
    if (cf.status.ok())
      compared.push_back(
          {std::string("closed form of ") + papers::kLandmarks + " (no ground truth)", cf,
           evaluate(cf, method, outside, seq, truth)});
  }
  const double scale = calibration::commandedScale(truth.truth);
  const CalibrationModel scaled = calibration::calibrateOracle(seq, truth, scale, config);
  compared.push_back(
      {"ground truth x odometry scale error " + fixed(scale, 4) + " (unseen by self-calibration)",
       scaled, evaluate(scaled, method, outside, seq, truth)});
  const CalibrationModel oracle = calibration::calibrateOracle(seq, truth, 1.0, config);
  compared.push_back({std::string("ground truth (oracle, ") + papers::kTriangulation + " ML)",
                      oracle, evaluate(oracle, method, outside, seq, truth)});
  return compared;
}

}  // namespace lidarcal::pipeline
