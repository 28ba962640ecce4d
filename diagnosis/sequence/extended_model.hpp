// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A sequence's extended model (step 5): the named effect's estimates and size, the scene keys
// that simulate it, how close its simulation comes to the data, and (with truth) the gain in
// calibration. Internal to the diagnosis library.

#include <map>
#include <string>
#include <vector>

#include "diagnosis/sequence/replicas.hpp"
#include "diagnosis/sequence/statistics.hpp"

namespace lidarcal::diagnosis::sequence {

/// Standardised residuals (under a baseline refit) of simulated data, with their groups.
struct ZSample {
  std::vector<double> z;    ///< standardised residuals (reading minus mean, over sigma)
  std::vector<long> group;  ///< each one's group: landmark x stop x edge
};

/// The standardised residuals of `rs`, appended to `sample` with their groups (landmark x stop x
/// edge).
void appendStandardised(ZSample& sample, const std::vector<ReadingRow>& rs);

/// How close a simulation comes to the measured data: the KS distance of the standardised
/// residuals and the median |ln variance ratio| over groups with 5 residuals or more on both sides.
Closeness closeness(const ZSample& measured, const ZSample& simulated);

/// The residual records of the report's plots.
std::vector<ResidualRecord> residualRecords(const std::vector<ReadingRow>& rs);

/// MSE ratio (Alhashimi et al. 2021 eq. 31) of a fitted model's correction of the readings against
/// the truth: the effect terms are taken off each reading, then f is inverted (LS).
double calibrationMseRatio(const LandmarkObservations& obs, const JointResult& fit,
                           const JointConfig& cfg, const std::vector<std::vector<double>>& truth);

/// Size of a fitted effect in the unit of its identifiability standard error (RMS over components).
double effectSize(Effect e, const JointResult& f);

/// The effect's fitted parameters, name with unit -> value (CandidateResult::estimates).
std::map<std::string, double> effectEstimates(Effect e, const JointResult& f);

/// The scene keys (docs/FORMAT.md) that simulate the effect as fitted, with the model beside it.
std::map<std::string, double> sceneKeys(Effect e, const JointResult& f, const ReplicaPlan& plan);

}  // namespace lidarcal::diagnosis::sequence
