// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal to drive_fit.cpp: the drive's least-squares problem over a DriveState. One Ceres
// problem holds a residual block per odometry step and per sighting or beam (normalised by their
// standard deviations, so that the cost is the negative log-likelihood up to a constant).
// Pose 0 fixes the world frame and held parameters are constant.

#include <memory>
#include <vector>

#include <ceres/ceres.h>

#include "odometry/drive_fit.hpp"

namespace lidarcal::odometry {

/// The kind of residual row `row` (in the order DriveProblem adds them: 3 per step, then 2 per
/// sighting; fitted by beam, 1 per beam and then 1 per sighting's bearing): 0 odometry translation,
/// 1 odometry heading, 2 range, 3 bearing.
int residualKind(std::size_t row, const DriveRecord& record);

/// Redundancy of each kind of residual at `state` (Foerstner's redundancy numbers summed by
/// kind: rows minus the trace of the hat matrix over them), for the variance factor of each.
Eigen::Vector4d redundancyByKind(const DriveRecord& record, const DriveState& state,
                                 const DriveFitSetup& setup);

/// Only the rank part of driveInformation(): whether the drive separates the estimated
/// parameters near `state` (read at the noise-free state there), with the directions it does not.
DriveInformation separability(const DriveRecord& record, const DriveState& state,
                              const DriveFitSetup& setup);

class DriveProblem {
 public:
  /// Builds the problem over a copy of `state`.
  DriveProblem(const DriveRecord& record, const DriveState& state, const DriveFitSetup& setup);

  ceres::Problem& problem() { return *problem_; }
  /// The free blocks in the order nuisance first (poses 1.., poles by id), then the estimated
  /// calibrated quantities in their order; nuisanceColumns() counts the first part's columns.
  const std::vector<double*>& freeBlocks() const { return free_blocks_; }
  int nuisanceColumns() const { return nuisance_columns_; }
  /// The estimated parameters' indices (0..7), in the order of freeBlocks()'s tail.
  const std::vector<int>& estimatedIndices() const { return estimated_; }
  /// The current values as a state.
  DriveState state() const;

 private:
  /// The calibrated quantities in three parameter blocks: wheels (r_L, r_R, b), mounting
  /// (l_x, l_y, l_theta), range (a_0, a_1); a held quantity is a constant part of its block.
  struct Group {
    int first, size;
  };
  static constexpr int kWheels = 0, kMount = 3, kRange = 6;
  static constexpr Group kGroups[] = {{kWheels, 3}, {kMount, 3}, {kRange, 2}};
  void holdWithin(const Group& g, const EstimatedSet& estimated);
  void addSteps(const DriveRecord& record, const DriveFitSetup& setup);
  void addSightings(const DriveRecord& record, const DriveFitSetup& setup);
  void addBeams(const DriveRecord& record, const DriveFitSetup& setup);

  std::vector<Eigen::Vector3d> poses_;
  std::map<int, Eigen::Vector2d> poles_;
  double globals_[kDriveParameterCount] = {};
  std::unique_ptr<ceres::Problem> problem_;
  std::vector<double*> free_blocks_;
  int nuisance_columns_ = 0;
  std::vector<int> estimated_;
};

}  // namespace lidarcal::odometry
