// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/drive_fit.hpp"

#include <cmath>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "common/pose2.hpp"
#include "common/ray_circle.hpp"
#include "common/stats_util.hpp"
#include "odometry/drive_problem.hpp"

namespace lidarcal::odometry {
namespace {

/// Each pole at the mean of where its sightings put it, seen from the dead-reckoned poses.
std::map<int, Eigen::Vector2d> placePoles(const DriveRecord& record,
                                          const std::vector<Eigen::Vector3d>& poses,
                                          const DriveParameters& p) {
  std::map<int, Eigen::Vector2d> sum;
  std::map<int, int> count;
  const OdometryParameters& o = p.odometry;
  for (const PoleSighting& s : record.sightings) {
    const Eigen::Vector3d laser =
        advance(poses[s.scan], {o.laser_x_m, o.laser_y_m, o.laser_theta_rad});
    const double distance =
        (s.range_m - p.range_offset_m) / (1.0 + p.range_scale) + record.pole_radius_m;
    const double heading = laser[2] + s.bearing_rad;
    sum.try_emplace(s.pole, Eigen::Vector2d::Zero()).first->second +=
        laser.head<2>() + distance * Eigen::Vector2d(std::cos(heading), std::sin(heading));
    ++count[s.pole];
  }
  for (auto& [id, total] : sum) total /= count[id];
  return sum;
}

Status checkRecord(const DriveRecord& record) {
  if (record.steps.empty() || record.sightings.empty())
    return {StatusCode::too_few_samples,
            "the drive needs at least one wheel step and one pole sighting: record the wheels' "
            "turns between scans and scans that see the poles"};
  const auto beyond = [&record](const char* what, std::size_t scan) {
    return Status{StatusCode::too_few_samples, std::string(what) + " names scan " +
                                                   std::to_string(scan) + " but the wheels cover " +
                                                   std::to_string(record.scans()) + " scans"};
  };
  std::set<int> sighted;
  for (const PoleSighting& s : record.sightings) {
    if (s.scan >= record.scans()) return beyond("a sighting", s.scan);
    sighted.insert(s.pole);
  }
  for (const BeamReading& b : record.beams) {
    if (b.scan >= record.scans()) return beyond("a beam", b.scan);
    if (sighted.count(b.pole) == 0)
      return {StatusCode::too_few_samples,
              "beams hit pole " + std::to_string(b.pole) + ", which no sighting places"};
  }
  return {};
}

}  // namespace

Vector8 DriveParameters::toVector() const {
  Vector8 v;
  v << odometry.toVector(), range_offset_m, range_scale;
  return v;
}

DriveParameters DriveParameters::fromVector(const Vector8& v) {
  return {OdometryParameters::fromVector(v.head<kParameterCount>()), v[6], v[7]};
}

Eigen::Vector3d advance(const Eigen::Vector3d& x, const Eigen::Vector3d& arc) {
  Eigen::Vector3d out;
  Pose2{x[0], x[1], x[2]}.toWorld(arc[0], arc[1], out[0], out[1]);
  out[2] = x[2] + arc[2];
  return out;
}

Eigen::Vector2d predictSighting(const Eigen::Vector3d& pose, const Eigen::Vector2d& pole,
                                const DriveParameters& params, double pole_radius_m) {
  const OdometryParameters& o = params.odometry;
  const Eigen::Vector3d laser = advance(pose, {o.laser_x_m, o.laser_y_m, 0.0});
  const Eigen::Vector2d w = pole - laser.head<2>();
  const double surface = w.norm() - pole_radius_m;
  const double bearing = std::atan2(w.y(), w.x()) - pose[2] - o.laser_theta_rad;
  return {surface * (1.0 + params.range_scale) + params.range_offset_m,
          std::remainder(bearing, 2.0 * kPi)};
}

double predictBeam(const Eigen::Vector3d& pose, const Eigen::Vector2d& pole,
                   const DriveParameters& params, double pole_radius_m, double angle_rad) {
  const OdometryParameters& o = params.odometry;
  const Eigen::Vector3d laser = advance(pose, {o.laser_x_m, o.laser_y_m, o.laser_theta_rad});
  const double d =
      rayCircleDistance(laser[0], laser[1], laser[2] + angle_rad, pole[0], pole[1], pole_radius_m);
  return d * (1.0 + params.range_scale) + params.range_offset_m;
}

DriveRecord centralBeams(const DriveRecord& record, double fraction) {
  std::map<std::pair<std::size_t, int>, Eigen::Vector2d> centre;  // laser frame, by (scan, pole)
  for (const PoleSighting& s : record.sightings)
    centre[{s.scan, s.pole}] = (s.range_m + record.pole_radius_m) *
                               Eigen::Vector2d(std::cos(s.bearing_rad), std::sin(s.bearing_rad));
  DriveRecord out = record;
  out.beams.clear();
  for (const BeamReading& b : record.beams) {
    const auto it = centre.find({b.scan, b.pole});
    if (it == centre.end()) continue;
    const double miss =
        it->second.y() * std::cos(b.angle_rad) - it->second.x() * std::sin(b.angle_rad);
    if (std::abs(miss) < fraction * record.pole_radius_m) out.beams.push_back(b);
  }
  return out;
}

Eigen::Vector2d stepSigmas(const WheelStep& step, const OdometryParameters& nominal,
                           const DriveNoise& noise) {
  const double left = nominal.left_radius_m * step.left_rad;
  const double right = nominal.right_radius_m * step.right_rad;
  const double distance = std::abs(left + right) / 2.0;
  const double turn = std::abs(right - left) / nominal.axle_m;
  return {std::sqrt(noise.slip_m_per_sqrt_m * noise.slip_m_per_sqrt_m * distance +
                    noise.floor_m * noise.floor_m),
          std::sqrt(noise.slip_rad_per_sqrt_rad * noise.slip_rad_per_sqrt_rad * turn +
                    noise.floor_rad * noise.floor_rad)};
}

std::vector<Eigen::Vector3d> deadReckoning(const DriveRecord& record,
                                           const OdometryParameters& params) {
  std::vector<Eigen::Vector3d> poses{Eigen::Vector3d::Zero()};
  for (const WheelStep& step : record.steps) {
    const Eigen::Vector3d arc = robotDisplacement(params.left_radius_m, params.right_radius_m,
                                                  params.axle_m, step.left_rad, step.right_rad);
    poses.push_back(advance(poses.back(), arc));
  }
  return poses;
}

namespace {

/// The variance factor and the squared residuals by kind, at the solution.
void summariseResiduals(const DriveRecord& record, const DriveFitSetup& setup,
                        DriveProblem& problem, DriveFit& out) {
  std::vector<double> r;
  ceres::Problem::EvaluateOptions options;
  options.num_threads = 1;
  problem.problem().Evaluate(options, nullptr, &r, nullptr, nullptr);
  for (std::size_t i = 0; i < r.size(); ++i)
    out.squared_by_kind[residualKind(i, record)] += r[i] * r[i];
  double free = problem.nuisanceColumns();
  for (bool e : setup.estimated) free += e ? 1.0 : 0.0;
  const double dof = static_cast<double>(r.size()) - free;
  out.variance_factor = dof > 0.0 ? out.squared_by_kind.sum() / dof : 0.0;
}

}  // namespace

Vector8 DriveFit::standardErrors() const {
  return information.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
}

VarianceByKind varianceByKind(const DriveRecord& record, const DriveFitSetup& setup,
                              const DriveFit& fit) {
  VarianceByKind out;
  out.redundancy = redundancyByKind(record, fit.state, setup);
  for (int k = 0; k < 4; ++k)
    out.factor[k] = out.redundancy[k] > 0.0 ? fit.squared_by_kind[k] / out.redundancy[k] : kNaN;
  return out;
}

DriveFit fitDrive(const DriveRecord& record, const DriveFitSetup& setup) {
  DriveFit out;
  out.status = checkRecord(record);
  if (!out.status.ok()) return out;
  DriveState start{setup.initial, deadReckoning(record, setup.initial.odometry), {}};
  start.poles = placePoles(record, start.poses, setup.initial);
  // a drive that cannot separate the parameters is refused before the fit
  if (DriveInformation first = separability(record, start, setup); !first.status.ok()) {
    out.state = start;
    out.information = std::move(first);
    out.status = out.information.status;
    return out;
  }
  DriveProblem problem(record, start, setup);
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = 200;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem.problem(), &summary);
  out.iterations = static_cast<int>(summary.iterations.size());
  out.cost = summary.final_cost;
  if (!summary.IsSolutionUsable() || !std::isfinite(summary.final_cost)) {
    out.status = {StatusCode::solver_failed,
                  "the solver found no usable solution: " + summary.message};
    return out;
  }
  out.state = problem.state();
  summariseResiduals(record, setup, problem, out);
  out.information = driveInformation(record, out.state, setup);
  out.status = out.information.status;
  return out;
}

}  // namespace lidarcal::odometry
