// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence.hpp"

#include <set>

#include "diagnosis/sequence/problem.hpp"
#include "diagnosis/skeleton.hpp"

namespace lidarcal::diagnosis {
namespace {

/// Size of the data: scans, stops, landmarks, readings.
void countData(const LandmarkObservations& obs, DiagnosisResult& out) {
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

}  // namespace

DiagnosisResult diagnoseSequence(const LandmarkObservations& obs, const DiagnoseConfig& config,
                                 const std::vector<std::vector<double>>* true_range_m) {
  config.validate();
  DiagnosisResult out;
  out.mode = DiagnoseMode::sequence;
  out.seed = config.seed;
  out.replicas = config.replicas;
  out.folds = config.folds;
  const std::vector<Effect> candidates = candidateList(config, DiagnoseMode::sequence);
  countData(obs, out);
  sequence::SequenceDiagnosis problem(obs, config, candidates, true_range_m);
  runDiagnosis(problem, config, candidates, out);
  return out;
}

}  // namespace lidarcal::diagnosis
