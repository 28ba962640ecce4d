// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/drive_problem.hpp"

#include <cmath>

#include "common/ray_circle.hpp"

namespace lidarcal::odometry {
namespace {

/// One odometry step: the poses' relative motion against the wheels' arc.
struct StepCost {
  WheelStep step;
  double inv_translation = 1.0;
  double inv_heading = 1.0;

  /// `wheels`: left radius, right radius, axle.
  template <typename T>
  bool operator()(const T* from, const T* to, const T* wheels, T* residual) const {
    using std::cos;
    using std::sin;
    const Eigen::Matrix<T, 3, 1> arc =
        robotDisplacement(wheels[0], wheels[1], wheels[2], step.left_rad, step.right_rad);
    const T dx = to[0] - from[0], dy = to[1] - from[1];
    const T c = cos(from[2]), s = sin(from[2]);
    residual[0] = (c * dx + s * dy - arc[0]) * T(inv_translation);
    residual[1] = (-s * dx + c * dy - arc[1]) * T(inv_translation);
    residual[2] = (to[2] - from[2] - arc[2]) * T(inv_heading);  // headings are continuous
    return true;
  }
};

/// The laser's origin in the world frame, from the robot's pose and the mounting's (x, y).
template <typename T>
void laserOrigin(const T* pose, const T* mount, T& x, T& y) {
  using std::cos;
  using std::sin;
  const T c = cos(pose[2]), s = sin(pose[2]);
  x = pose[0] + c * mount[0] - s * mount[1];
  y = pose[1] + s * mount[0] + c * mount[1];
}

/// The pole's centre in the laser frame.
template <typename T>
void centreInLaser(const T* pose, const T* pole, const T* mount, T& px, T& py) {
  using std::cos;
  using std::sin;
  T lx, ly;
  laserOrigin(pose, mount, lx, ly);
  const T heading = pose[2] + mount[2];
  const T ch = cos(heading), sh = sin(heading);
  const T wx = pole[0] - lx, wy = pole[1] - ly;
  px = ch * wx + sh * wy;
  py = -sh * wx + ch * wy;
}

/// The angle from the measured direction (cos, sin) to the centre at (px, py), through +-pi
/// without a jump.
template <typename T>
T bearingError(double bearing_cos, double bearing_sin, const T& px, const T& py) {
  using std::atan2;
  const T cross = T(bearing_cos) * py - T(bearing_sin) * px;
  const T dot = T(bearing_cos) * px + T(bearing_sin) * py;
  return atan2(cross, dot);
}

/// One sighting: range to the surface through the bias polynomial, and the centre's bearing.
struct SightingCost {
  double range_m;
  double bearing_cos, bearing_sin;
  double pole_radius_m;
  double inv_range, inv_bearing;

  /// `mount`: laser x, y, heading; `range`: offset, scale.
  template <typename T>
  bool operator()(const T* pose, const T* pole, const T* mount, const T* range, T* residual) const {
    using std::sqrt;
    T px, py;
    centreInLaser(pose, pole, mount, px, py);
    const T distance = sqrt(px * px + py * py);
    const T predicted = (distance - T(pole_radius_m)) * (T(1.0) + range[1]) + range[0];
    residual[0] = (T(range_m) - predicted) * T(inv_range);
    residual[1] = bearingError(bearing_cos, bearing_sin, px, py) * T(inv_bearing);
    return true;
  }
};

/// The bearing of a sighting alone (fitted by beam: the ranges come from the beams, the
/// centre's direction from which beams hit).
struct BearingCost {
  double bearing_cos, bearing_sin;
  double inv_bearing;

  template <typename T>
  bool operator()(const T* pose, const T* pole, const T* mount, T* residual) const {
    T px, py;
    centreInLaser(pose, pole, mount, px, py);
    residual[0] = bearingError(bearing_cos, bearing_sin, px, py) * T(inv_bearing);
    return true;
  }
};

/// One beam: its reading against the distance along it to the pole's circle, through the bias.
struct BeamCost {
  double angle_rad;
  double range_m;
  double pole_radius_m;
  double inv_range;

  template <typename T>
  bool operator()(const T* pose, const T* pole, const T* mount, const T* range, T* residual) const {
    T lx, ly;
    laserOrigin(pose, mount, lx, ly);
    const T d = rayCircleDistance(lx, ly, pose[2] + mount[2] + T(angle_rad), pole[0], pole[1],
                                  T(pole_radius_m));
    residual[0] = (T(range_m) - d * (T(1.0) + range[1]) - range[0]) * T(inv_range);
    return true;
  }
};

}  // namespace

DriveProblem::DriveProblem(const DriveRecord& record, const DriveState& state,
                           const DriveFitSetup& setup)
    : poses_(state.poses), poles_(state.poles) {
  const Vector8 v = state.params.toVector();
  for (int i = 0; i < kDriveParameterCount; ++i) globals_[i] = v[i];
  problem_ = std::make_unique<ceres::Problem>();
  addSteps(record, setup);
  if (record.byBeam())
    addBeams(record, setup);
  else
    addSightings(record, setup);
  for (const Group& g : kGroups) problem_->AddParameterBlock(&globals_[g.first], g.size);

  problem_->SetParameterBlockConstant(poses_[0].data());
  for (std::size_t k = 1; k < poses_.size(); ++k) free_blocks_.push_back(poses_[k].data());
  int sighted = 0;  // poles in the problem: a pole no scan saw has no block
  for (auto& [id, centre] : poles_) {
    if (!problem_->HasParameterBlock(centre.data())) continue;
    free_blocks_.push_back(centre.data());
    ++sighted;
  }
  nuisance_columns_ = 3 * static_cast<int>(poses_.size() - 1) + 2 * sighted;
  for (const Group& g : kGroups) holdWithin(g, setup.estimated);
}

void DriveProblem::addSteps(const DriveRecord& record, const DriveFitSetup& setup) {
  for (std::size_t k = 0; k < record.steps.size(); ++k) {
    const Eigen::Vector2d sigma = stepSigmas(record.steps[k], setup.noiseNominal(), setup.noise);
    auto* cost = new ceres::AutoDiffCostFunction<StepCost, 3, 3, 3, 3>(
        new StepCost{record.steps[k], 1.0 / sigma[0], 1.0 / sigma[1]});
    problem_->AddResidualBlock(cost, nullptr, poses_[k].data(), poses_[k + 1].data(),
                               &globals_[kWheels]);
  }
}

void DriveProblem::addSightings(const DriveRecord& record, const DriveFitSetup& setup) {
  for (const PoleSighting& s : record.sightings) {
    auto* cost = new ceres::AutoDiffCostFunction<SightingCost, 2, 3, 2, 3, 2>(new SightingCost{
        s.range_m, std::cos(s.bearing_rad), std::sin(s.bearing_rad), record.pole_radius_m,
        1.0 / setup.noise.range_sigma_m, 1.0 / setup.noise.bearing_sigma_rad});
    problem_->AddResidualBlock(cost, nullptr, poses_[s.scan].data(), poles_.at(s.pole).data(),
                               &globals_[kMount], &globals_[kRange]);
  }
}

void DriveProblem::addBeams(const DriveRecord& record, const DriveFitSetup& setup) {
  for (const BeamReading& b : record.beams) {
    auto* cost = new ceres::AutoDiffCostFunction<BeamCost, 1, 3, 2, 3, 2>(new BeamCost{
        b.angle_rad, b.range_m, record.pole_radius_m, 1.0 / setup.noise.range_sigma_m});
    problem_->AddResidualBlock(cost, nullptr, poses_[b.scan].data(), poles_.at(b.pole).data(),
                               &globals_[kMount], &globals_[kRange]);
  }
  for (const PoleSighting& s : record.sightings) {
    auto* cost = new ceres::AutoDiffCostFunction<BearingCost, 1, 3, 2, 3>(new BearingCost{
        std::cos(s.bearing_rad), std::sin(s.bearing_rad), 1.0 / setup.noise.bearing_sigma_rad});
    problem_->AddResidualBlock(cost, nullptr, poses_[s.scan].data(), poles_.at(s.pole).data(),
                               &globals_[kMount]);
  }
}

void DriveProblem::holdWithin(const Group& g, const EstimatedSet& estimated) {
  double* block = &globals_[g.first];
  std::vector<int> held;
  for (int i = 0; i < g.size; ++i) {
    if (estimated[g.first + i])
      estimated_.push_back(g.first + i);  // its column: the block's tangent space keeps the order
    else
      held.push_back(i);
  }
  if (static_cast<int>(held.size()) == g.size) {
    problem_->SetParameterBlockConstant(block);
    return;
  }
  if (!held.empty()) problem_->SetManifold(block, new ceres::SubsetManifold(g.size, held));
  free_blocks_.push_back(block);
}

DriveState DriveProblem::state() const {
  Vector8 v;
  for (int i = 0; i < kDriveParameterCount; ++i) v[i] = globals_[i];
  return DriveState{DriveParameters::fromVector(v), poses_, poles_};
}

}  // namespace lidarcal::odometry
