// SPDX-License-Identifier: BSD-3-Clause
// The Fisher information of the calibrated quantities with the poses and poles eliminated:
// with J the normalised residuals' Jacobian, I = J'J split into nuisance (N) and calibrated (G)
// columns, the information of G is the Schur complement I_GG - I_GN I_NN^-1 I_NG.
// Which combinations the data cannot separate is a property of the model and the drive's
// geometry, not of one draw of its noise: the odometry residuals are homogeneous in the scale of
// the world, so at noisy poses a common scale gains a sliver of information from the noise
// itself. The rank is therefore read at the nearby state the model says noise-free data would
// have: the poses the wheels give and the sightings those poses predict.
#include <optional>
#include <utility>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "odometry/drive_fit.hpp"
#include "odometry/drive_problem.hpp"

namespace lidarcal::odometry {
namespace {

/// Below this ratio to the largest eigenvalue of the normalised information a direction is
/// taken as undetermined (double precision leaves about 1e-16 of the largest).
constexpr double kSingularRatio = 1e-10;

/// The normalised residuals' Jacobian over the free blocks, rows in residual order.
Eigen::SparseMatrix<double, Eigen::RowMajor> jacobianOf(DriveProblem& problem) {
  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = problem.freeBlocks();
  options.apply_loss_function = false;
  options.num_threads = 1;
  ceres::CRSMatrix jacobian;
  problem.problem().Evaluate(options, nullptr, nullptr, nullptr, &jacobian);
  return Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor>>(
      jacobian.num_rows, jacobian.num_cols, static_cast<int>(jacobian.values.size()),
      jacobian.rows.data(), jacobian.cols.data(), jacobian.values.data());
}

Eigen::SparseMatrix<double> normalMatrix(DriveProblem& problem) {
  const Eigen::SparseMatrix<double> j = jacobianOf(problem);
  return Eigen::SparseMatrix<double>(j.transpose() * j);
}

/// The reduced information of the estimated parameters at `state`, or nothing when the poses
/// and poles are not tied down.
std::optional<Eigen::MatrixXd> reducedInformation(const DriveRecord& record,
                                                  const DriveState& state,
                                                  const DriveFitSetup& setup) {
  DriveProblem problem(record, state, setup);
  const Eigen::SparseMatrix<double> normal = normalMatrix(problem);
  const int n = problem.nuisanceColumns();
  const int g = static_cast<int>(problem.estimatedIndices().size());
  const Eigen::SparseMatrix<double> nn = normal.topLeftCorner(n, n);
  const Eigen::MatrixXd ng = Eigen::MatrixXd(normal.topRightCorner(n, g));
  Eigen::MatrixXd reduced = Eigen::MatrixXd(normal.bottomRightCorner(g, g));
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> nuisance(nn);
  if (nuisance.info() != Eigen::Success) return std::nullopt;
  reduced -= ng.transpose() * nuisance.solve(ng);
  return Eigen::MatrixXd(0.5 * (reduced + reduced.transpose()));
}

/// The state noise-free data would give near `state`, with the sightings and beams it predicts.
std::pair<DriveRecord, DriveState> noiseFree(const DriveRecord& record, const DriveState& state) {
  std::pair<DriveRecord, DriveState> out{record, state};
  const std::vector<Eigen::Vector3d>& poses = out.second.poses =
      deadReckoning(record, state.params.odometry);
  for (PoleSighting& s : out.first.sightings) {
    const Eigen::Vector2d seen =
        predictSighting(poses[s.scan], state.poles.at(s.pole), state.params, record.pole_radius_m);
    s.range_m = seen[0];
    s.bearing_rad = seen[1];
  }
  for (BeamReading& b : out.first.beams)
    b.range_m = predictBeam(poses[b.scan], state.poles.at(b.pole), state.params,
                            record.pole_radius_m, b.angle_rad);
  return out;
}

/// Directions in parameter units (largest component 1) along which `reduced` is singular to
/// double precision.
std::vector<Vector8> nullDirections(const Eigen::MatrixXd& reduced,
                                    const std::vector<int>& estimated) {
  const int g = static_cast<int>(estimated.size());
  Eigen::VectorXd scale(g);
  for (int a = 0; a < g; ++a) scale[a] = reduced(a, a) > 0.0 ? 1.0 / std::sqrt(reduced(a, a)) : 0.0;
  const Eigen::MatrixXd normalised = scale.asDiagonal() * reduced * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(normalised);
  const double largest = eigen.eigenvalues().maxCoeff();
  std::vector<Vector8> out;
  for (int a = 0; a < g; ++a) {
    if (eigen.eigenvalues()[a] > kSingularRatio * largest && scale[a] > 0.0) continue;
    Vector8 direction = Vector8::Zero();
    for (int b = 0; b < g; ++b) direction[estimated[b]] = scale[b] * eigen.eigenvectors()(b, a);
    out.push_back(direction / direction.cwiseAbs().maxCoeff());
  }
  return out;
}

}  // namespace

int residualKind(std::size_t row, const DriveRecord& record) {
  const std::size_t steps = record.steps.size();
  if (row < 3 * steps) return row % 3 == 2 ? 1 : 0;
  if (record.byBeam()) return row < 3 * steps + record.beams.size() ? 2 : 3;
  return (row - 3 * steps) % 2 == 0 ? 2 : 3;
}

Eigen::Vector4d redundancyByKind(const DriveRecord& record, const DriveState& state,
                                 const DriveFitSetup& setup) {
  DriveProblem problem(record, state, setup);
  const Eigen::SparseMatrix<double, Eigen::RowMajor> j = jacobianOf(problem);
  const Eigen::SparseMatrix<double> normal = Eigen::SparseMatrix<double>(j.transpose() * j);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(normal);
  Eigen::Vector4d rows = Eigen::Vector4d::Zero(), leverage = Eigen::Vector4d::Zero();
  if (ldlt.info() != Eigen::Success) return rows;
  Eigen::VectorXd row(j.cols());
  for (Eigen::Index i = 0; i < j.rows(); ++i) {
    row = Eigen::VectorXd(j.row(i).transpose());
    const int kind = residualKind(static_cast<std::size_t>(i), record);
    rows[kind] += 1.0;
    leverage[kind] += row.dot(ldlt.solve(row));  // h_ii = j_i' (J'J)^-1 j_i
  }
  return rows - leverage;
}

namespace {

const char* const kUntied =
    "the poses and poles are not determined by the steps and sightings (a pole or a stretch of "
    "the drive is not tied to the rest)";
const char* const kInseparable =
    "the drive leaves a combination of the estimated parameters undetermined: hold one of them at "
    "a measured value, or drive turns and straight lines among the poles";

std::vector<int> estimatedIndices(const DriveFitSetup& setup) {
  std::vector<int> estimated;
  for (int i = 0; i < kDriveParameterCount; ++i)
    if (setup.estimated[i]) estimated.push_back(i);
  return estimated;
}

}  // namespace

DriveInformation separability(const DriveRecord& record, const DriveState& state,
                              const DriveFitSetup& setup) {
  DriveInformation out;
  const auto [clean_record, clean_state] = noiseFree(record, state);
  const std::optional<Eigen::MatrixXd> clean = reducedInformation(clean_record, clean_state, setup);
  if (!clean) {
    out.status = {StatusCode::not_identifiable, kUntied};
    return out;
  }
  out.inseparable = nullDirections(*clean, estimatedIndices(setup));
  if (!out.inseparable.empty()) out.status = {StatusCode::not_identifiable, kInseparable};
  return out;
}

DriveInformation driveInformation(const DriveRecord& record, const DriveState& state,
                                  const DriveFitSetup& setup) {
  DriveInformation out = separability(record, state, setup);
  if (!out.status.ok()) return out;
  const std::optional<Eigen::MatrixXd> reduced = reducedInformation(record, state, setup);
  if (!reduced) {
    out.status = {StatusCode::not_identifiable, kUntied};
    return out;
  }
  const std::vector<int> estimated = estimatedIndices(setup);
  const int g = static_cast<int>(estimated.size());
  const Eigen::MatrixXd inverse = reduced->ldlt().solve(Eigen::MatrixXd::Identity(g, g));
  for (int a = 0; a < g; ++a) {
    for (int b = 0; b < g; ++b) {
      out.information(estimated[a], estimated[b]) = (*reduced)(a, b);
      out.covariance(estimated[a], estimated[b]) = inverse(a, b);
    }
  }
  return out;
}

}  // namespace lidarcal::odometry
