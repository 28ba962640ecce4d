#include "noise/ml.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <ceres/ceres.h>

#include "common/errors.hpp"

namespace lidarcal::noise {
namespace {

// ---- The model: residuals and Jacobians (shared by Ceres and the redundancy computation) ----

/// Linearised observation: residual (model - reading) and Jacobians of range (row 0) and
/// bearing (row 1) w.r.t. the pose (x, y, theta) and the landmark (x, y). The bias enters with
/// derivative 1 on its own component.
struct ObservationLinear {
  double res[2];
  double d_pose[2][3];
  double d_landmark[2][2];
};

void linearizeObservation(const Pose2& pose, const double* lm, const double* bias, const Observation& o,
                          ObservationLinear& out) {
  const double dx = lm[0] - pose.x_m, dy = lm[1] - pose.y_m;
  const double q = std::max(dx * dx + dy * dy, 1e-18), rho = std::sqrt(q);
  out.res[0] = rho + bias[0] - o.range_m;
  out.res[1] = wrapAngle(std::atan2(dy, dx) - pose.yaw_rad + bias[1] - o.bearing_rad);
  out.d_pose[0][0] = -dx / rho, out.d_pose[0][1] = -dy / rho, out.d_pose[0][2] = 0.0;
  out.d_pose[1][0] = dy / q, out.d_pose[1][1] = -dx / q, out.d_pose[1][2] = -1.0;
  out.d_landmark[0][0] = dx / rho, out.d_landmark[0][1] = dy / rho;
  out.d_landmark[1][0] = -dy / q, out.d_landmark[1][1] = dx / q;
}

/// Linearised motion residual: relative pose of b in the frame of a, minus the command.
struct OdometryLinear {
  double res[3];
  double d_a[3][3];
  double d_b[3][3];
};

void linearizeOdometry(const Pose2& a, const Pose2& b, const OdometryStep& u, OdometryLinear& out) {
  const double c = std::cos(a.yaw_rad), s = std::sin(a.yaw_rad);
  const double ddx = b.x_m - a.x_m, ddy = b.y_m - a.y_m;
  const double rx = c * ddx + s * ddy, ry = -s * ddx + c * ddy;
  out.res[0] = rx - u.dx_m;
  out.res[1] = ry - u.dy_m;
  out.res[2] = wrapAngle(b.yaw_rad - a.yaw_rad - u.dtheta_rad);
  const double da[3][3] = {{-c, -s, ry}, {s, -c, -rx}, {0.0, 0.0, -1.0}};
  const double db[3][3] = {{c, s, 0.0}, {-s, c, 0.0}, {0.0, 0.0, 1.0}};
  std::copy(&da[0][0], &da[0][0] + 9, &out.d_a[0][0]);
  std::copy(&db[0][0], &db[0][0] + 9, &out.d_b[0][0]);
}

Pose2 poseOf(const double* p) { return Pose2{p[0], p[1], p[2]}; }

// ---- Ceres cost functions: whitened by the current 1/sigma of their groups ----

class ObservationCost final : public ceres::CostFunction {
 public:
  ObservationCost(const Observation& o, bool with_pose, const double* inv_sigma)
      : o_(o), with_pose_(with_pose), inv_sigma_(inv_sigma) {
    set_num_residuals(2);
    if (with_pose_) mutable_parameter_block_sizes()->push_back(3);
    mutable_parameter_block_sizes()->push_back(2);
    mutable_parameter_block_sizes()->push_back(2);
  }
  bool Evaluate(double const* const* p, double* r, double** J) const override {
    const int l = with_pose_ ? 1 : 0;
    ObservationLinear lin;
    linearizeObservation(with_pose_ ? poseOf(p[0]) : Pose2{}, p[l], p[l + 1], o_, lin);
    const double w[2] = {inv_sigma_[0], inv_sigma_[1]};
    for (int c = 0; c < 2; ++c) r[c] = w[c] * lin.res[c];
    if (!J) return true;
    for (int c = 0; c < 2; ++c) {
      if (with_pose_ && J[0])
        for (int i = 0; i < 3; ++i) J[0][c * 3 + i] = w[c] * lin.d_pose[c][i];
      if (J[l])
        for (int i = 0; i < 2; ++i) J[l][c * 2 + i] = w[c] * lin.d_landmark[c][i];
      if (J[l + 1])
        for (int i = 0; i < 2; ++i) J[l + 1][c * 2 + i] = i == c ? w[c] : 0.0;
    }
    return true;
  }

 private:
  Observation o_;
  bool with_pose_;
  const double* inv_sigma_;  // range, bearing of this observation's sensor
};

class OdometryCost final : public ceres::CostFunction {
 public:
  OdometryCost(const OdometryStep& u, bool from_origin, const double* inv_sigma)
      : u_(u), from_origin_(from_origin), inv_sigma_(inv_sigma) {
    set_num_residuals(3);
    if (!from_origin_) mutable_parameter_block_sizes()->push_back(3);
    mutable_parameter_block_sizes()->push_back(3);
  }
  bool Evaluate(double const* const* p, double* r, double** J) const override {
    const int b = from_origin_ ? 0 : 1;
    OdometryLinear lin;
    linearizeOdometry(from_origin_ ? Pose2{} : poseOf(p[0]), poseOf(p[b]), u_, lin);
    for (int c = 0; c < 3; ++c) r[c] = inv_sigma_[c] * lin.res[c];
    if (!J) return true;
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < 3; ++i) {
        if (!from_origin_ && J[0]) J[0][c * 3 + i] = inv_sigma_[c] * lin.d_a[c][i];
        if (J[b]) J[b][c * 3 + i] = inv_sigma_[c] * lin.d_b[c][i];
      }
    return true;
  }

 private:
  OdometryStep u_;
  bool from_origin_;
  const double* inv_sigma_;  // dx, dy, dtheta
};

std::vector<std::string> groupNames(int sensors) {
  std::vector<std::string> names;
  for (int s = 0; s < sensors; ++s) {
    names.push_back("s" + std::to_string(s) + ".range");
    names.push_back("s" + std::to_string(s) + ".bearing");
  }
  for (const char* n : {"process.dx", "process.dy", "process.dtheta"}) names.push_back(n);
  return names;
}

Pose2 compose(const Pose2& pose, const OdometryStep& u) {
  Pose2 out;
  pose.toWorld(u.dx_m, u.dy_m, out.x_m, out.y_m);
  out.yaw_rad = wrapAngle(pose.yaw_rad + u.dtheta_rad);
  return out;
}

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

}  // namespace

void MlNoiseConfig::validate() const {
  if (max_iterations < 1) throw InputError("", "max_iterations", "must be at least 1");
  if (!(tolerance > 0.0)) throw InputError("", "tolerance", "must be positive");
  if (!(min_variance > 0.0)) throw InputError("", "min_variance", "must be positive");
  if (solver_iterations < 1) throw InputError("", "solver_iterations", "must be at least 1");
  if (max_motions_for_information < 0) throw InputError("", "max_motions_for_information", "must be at least 0");
  for (const auto& s : initial.sensors)
    if (!(s.range_var_m2 > 0.0) || !(s.bearing_var_rad2 > 0.0))
      throw InputError("", "initial noise", "sensor variances must be positive");
}

MlState initialState(const NoiseProblem& problem) {
  MlState st;
  st.poses.push_back(Pose2{});
  for (int k = 1; k < problem.stops; ++k)
    st.poses.push_back(compose(st.poses.back(), problem.odometry[static_cast<std::size_t>(k)]));
  st.landmarks.assign(static_cast<std::size_t>(problem.landmarks), {0.0, 0.0});
  std::vector<int> count(static_cast<std::size_t>(problem.landmarks), 0);
  for (const auto& o : problem.observations) {
    const Pose2& p = st.poses[static_cast<std::size_t>(o.stop)];
    double wx = 0.0, wy = 0.0;
    p.toWorld(o.range_m * std::cos(o.bearing_rad), o.range_m * std::sin(o.bearing_rad), wx, wy);
    auto& lm = st.landmarks[static_cast<std::size_t>(o.landmark)];
    lm[0] += wx;
    lm[1] += wy;
    ++count[static_cast<std::size_t>(o.landmark)];
  }
  for (std::size_t j = 0; j < st.landmarks.size(); ++j) {
    st.landmarks[j][0] /= count[j];
    st.landmarks[j][1] /= count[j];
  }
  st.biases.assign(static_cast<std::size_t>(problem.sensors), {0.0, 0.0});
  return st;
}

std::vector<double> residualsAt(const NoiseProblem& problem, const MlState& state, std::vector<int>* group) {
  std::vector<double> r;
  if (group) group->clear();
  const int S = problem.sensors;
  for (const auto& o : problem.observations) {
    ObservationLinear lin;
    linearizeObservation(state.poses[static_cast<std::size_t>(o.stop)], state.landmarks[static_cast<std::size_t>(o.landmark)].data(),
                         state.biases[static_cast<std::size_t>(o.sensor)].data(), o, lin);
    for (int c = 0; c < 2; ++c) {
      r.push_back(lin.res[c]);
      if (group) group->push_back(2 * o.sensor + c);
    }
  }
  for (int k = 1; k < problem.stops; ++k) {
    OdometryLinear lin;
    linearizeOdometry(state.poses[static_cast<std::size_t>(k - 1)], state.poses[static_cast<std::size_t>(k)],
                      problem.odometry[static_cast<std::size_t>(k)], lin);
    for (int c = 0; c < 3; ++c) {
      r.push_back(lin.res[c]);
      if (group) group->push_back(2 * S + c);
    }
  }
  return r;
}

namespace {

struct AdjustmentAnalysis {
  std::vector<double> redundancy;       // per group: sum of the redundancy numbers r_ii
  std::vector<double> redundancy_sq;    // per group: sum of r_ii^2 (diagonal Fisher information of the variance)
  double log_det_normal = 0.0;          // log det N (whitened normal matrix)
  std::vector<double> bias_std;         // per sensor, range and bearing interleaved (NaN when not estimated)
  Eigen::MatrixXd fisher;               // with_information: G x G information of the variances (see below)
};

/// One whitened observation row: pose part (3, when the stop is not 0) and z part (indices, values).
struct ObsRow {
  int p;          // pose index (stop - 1) or -1
  Vec3 ap;
  int nz;
  int cols[3];
  double az[3];
};

/// One whitened motion row.
struct OdoRow {
  int pa, pb;  // pose indices (pa = -1: from the fixed origin)
  Vec3 aa, ab;
};

/// The normal matrix of the adjustment, its structured inverse and the redundancy numbers.
/// Unknowns: poses 1..K-1 (y, 3 each, block-tridiagonal normal matrix D through the motion
/// chain) and z = landmarks (2 each) then biases (2 each, when estimated). With B = N_yz and
/// C = N_zz: E = D^-1 B, S = C - B^T E, and
///   (N^-1)_zz = S^-1, (N^-1)_yz = -E S^-1, (N^-1)_yy = D^-1 + E S^-1 E^T,
/// of which only the diagonal and first off-diagonal pose blocks of D^-1 are needed (backward
/// recursion over the chain). Leverage of a whitened row a: h = a^T N^-1 a; r_g = sum(1 - h).
class AdjustmentAnalyser {
 public:
  AdjustmentAnalyser(const NoiseProblem& problem, const MlState& state, const std::vector<double>& variances, bool with_biases);
  AdjustmentAnalysis analyse(bool with_information);

 private:
  int biasCol(int s, int c) const { return 2 * L_ + 2 * s + c; }
  void observationRows();
  void odometryRows();
  void eliminateChain();
  void solveChain(Eigen::MatrixXd& M) const;
  void invertBlocks();
  void redundancies(AdjustmentAnalysis& out) const;
  Eigen::MatrixXd motionTraces() const;
  void information(AdjustmentAnalysis& out) const;

  const NoiseProblem& problem_;
  const MlState& state_;
  const std::vector<double>& variances_;
  const bool with_biases_;
  const int S_, K_, L_, P_, m_;
  const std::size_t uP_;
  std::vector<Mat3> Dd_, Do_;     // D: diagonal and first off-diagonal pose blocks
  Eigen::MatrixXd B_, C_;         // N_yz, N_zz
  std::vector<ObsRow> obs_rows_;
  std::vector<int> obs_group_;
  std::vector<OdoRow> odo_rows_;
  std::vector<int> odo_group_;
  std::vector<Mat3> Pinv_;        // inverses of the pose Schur blocks (forward elimination)
  double log_det_ = 0.0;          // log det N = sum log det(pose Schur blocks) + log det S
  Eigen::MatrixXd E_, Sinv_, F_;  // D^-1 B, S^-1, E S^-1
  std::vector<Mat3> Mdiag_, Mnext_;  // (N^-1) blocks of a pose with itself and with the next pose
};

AdjustmentAnalyser::AdjustmentAnalyser(const NoiseProblem& problem, const MlState& state, const std::vector<double>& variances,
                                       bool with_biases)
    : problem_(problem),
      state_(state),
      variances_(variances),
      with_biases_(with_biases),
      S_(problem.sensors),
      K_(problem.stops),
      L_(problem.landmarks),
      P_(K_ - 1),
      m_(2 * L_ + (with_biases ? 2 * S_ : 0)),
      uP_(static_cast<std::size_t>(std::max(P_, 0))),
      Dd_(uP_, Mat3::Zero()),
      Do_(uP_ > 0 ? uP_ - 1 : 0, Mat3::Zero()),
      B_(Eigen::MatrixXd::Zero(3 * std::max(P_, 0), m_)),
      C_(Eigen::MatrixXd::Zero(m_, m_)) {}

void AdjustmentAnalyser::observationRows() {
  obs_rows_.reserve(problem_.observations.size() * 2);
  for (const auto& o : problem_.observations) {
    ObservationLinear lin;
    linearizeObservation(state_.poses[static_cast<std::size_t>(o.stop)], state_.landmarks[static_cast<std::size_t>(o.landmark)].data(),
                         state_.biases[static_cast<std::size_t>(o.sensor)].data(), o, lin);
    for (int c = 0; c < 2; ++c) {
      const int g = 2 * o.sensor + c;
      const double w = 1.0 / std::sqrt(variances_[static_cast<std::size_t>(g)]);
      ObsRow row;
      row.p = o.stop - 1;
      row.ap = w * Vec3(lin.d_pose[c][0], lin.d_pose[c][1], lin.d_pose[c][2]);
      row.nz = 2;
      row.cols[0] = 2 * o.landmark, row.cols[1] = 2 * o.landmark + 1;
      row.az[0] = w * lin.d_landmark[c][0], row.az[1] = w * lin.d_landmark[c][1];
      if (with_biases_) {
        row.cols[2] = biasCol(o.sensor, c);
        row.az[2] = w;
        row.nz = 3;
      }
      if (row.p >= 0) {
        Dd_[static_cast<std::size_t>(row.p)] += row.ap * row.ap.transpose();
        for (int i = 0; i < row.nz; ++i) B_.block(3 * row.p, row.cols[i], 3, 1) += row.ap * row.az[i];
      }
      for (int i = 0; i < row.nz; ++i)
        for (int j = 0; j < row.nz; ++j) C_(row.cols[i], row.cols[j]) += row.az[i] * row.az[j];
      obs_rows_.push_back(row);
      obs_group_.push_back(g);
    }
  }
}

void AdjustmentAnalyser::odometryRows() {
  for (int k = 1; k < K_; ++k) {
    OdometryLinear lin;
    linearizeOdometry(state_.poses[static_cast<std::size_t>(k - 1)], state_.poses[static_cast<std::size_t>(k)],
                      problem_.odometry[static_cast<std::size_t>(k)], lin);
    for (int c = 0; c < 3; ++c) {
      const int g = 2 * S_ + c;
      const double w = 1.0 / std::sqrt(variances_[static_cast<std::size_t>(g)]);
      OdoRow row{k - 2, k - 1, w * Vec3(lin.d_a[c][0], lin.d_a[c][1], lin.d_a[c][2]),
                 w * Vec3(lin.d_b[c][0], lin.d_b[c][1], lin.d_b[c][2])};
      Dd_[static_cast<std::size_t>(row.pb)] += row.ab * row.ab.transpose();
      if (row.pa >= 0) {
        Dd_[static_cast<std::size_t>(row.pa)] += row.aa * row.aa.transpose();
        Do_[static_cast<std::size_t>(row.pa)] += row.aa * row.ab.transpose();
      }
      odo_rows_.push_back(row);
      odo_group_.push_back(g);
    }
  }
}

template <class Llt>
void addLogDet(const Llt& llt, double& log_det) {
  for (Eigen::Index i = 0; i < llt.matrixLLT().rows(); ++i) log_det += 2.0 * std::log(llt.matrixLLT()(i, i));
}

/// Block-tridiagonal elimination of the pose chain (forward).
void AdjustmentAnalyser::eliminateChain() {
  Pinv_.resize(uP_);
  for (std::size_t p = 0; p < uP_; ++p) {
    Mat3 schur = Dd_[p];
    if (p > 0) schur -= Do_[p - 1].transpose() * Pinv_[p - 1] * Do_[p - 1];
    Eigen::LLT<Mat3> llt(schur);
    if (llt.info() != Eigen::Success)
      throw DataError("", "pose " + std::to_string(p + 1), "is not determined by the data (singular normal matrix)",
                      "check the odometry and that every stop is connected to the previous one");
    addLogDet(llt, log_det_);
    Pinv_[p] = llt.solve(Mat3::Identity());
  }
}

/// M <- D^-1 M for a 3P-row matrix: forward elimination, then back substitution.
void AdjustmentAnalyser::solveChain(Eigen::MatrixXd& M) const {
  for (std::size_t p = 1; p < uP_; ++p)
    M.middleRows(3 * static_cast<Eigen::Index>(p), 3) -=
        Do_[p - 1].transpose() * Pinv_[p - 1] * M.middleRows(3 * static_cast<Eigen::Index>(p - 1), 3);
  for (std::size_t p = uP_; p-- > 0;) {
    Eigen::MatrixXd y = M.middleRows(3 * static_cast<Eigen::Index>(p), 3);
    if (p + 1 < uP_) y -= Do_[p] * M.middleRows(3 * static_cast<Eigen::Index>(p + 1), 3);
    M.middleRows(3 * static_cast<Eigen::Index>(p), 3) = Pinv_[p] * y;
  }
}

/// D^-1 B and the selected blocks of D^-1 (backward), S^-1, and the pose blocks of N^-1.
void AdjustmentAnalyser::invertBlocks() {
  E_ = B_;  // becomes D^-1 B
  solveChain(E_);
  std::vector<Mat3> Gd(uP_), Go(uP_ > 0 ? uP_ - 1 : 0);
  for (std::size_t p = uP_; p-- > 0;) {
    if (p + 1 == uP_) {
      Gd[p] = Pinv_[p];
      continue;
    }
    Go[p] = -Pinv_[p] * Do_[p] * Gd[p + 1];
    Gd[p] = Pinv_[p] - Go[p] * Do_[p].transpose() * Pinv_[p];
  }
  if (m_ > 0) {
    const Eigen::MatrixXd Sz = C_ - B_.transpose() * E_;
    Eigen::LLT<Eigen::MatrixXd> llt(Sz);
    if (llt.info() != Eigen::Success)
      throw DataError("", "landmarks and biases", "are not determined by the data (singular normal matrix)",
                      "biases need translation in the odometry; every landmark needs an observation");
    addLogDet(llt, log_det_);
    Sinv_ = llt.solve(Eigen::MatrixXd::Identity(m_, m_));
  }
  F_ = m_ > 0 ? Eigen::MatrixXd(E_ * Sinv_) : Eigen::MatrixXd(3 * std::max(P_, 0), 0);
  Mdiag_.resize(uP_);
  Mnext_.resize(uP_ > 0 ? uP_ - 1 : 0);
  for (std::size_t p = 0; p < uP_; ++p) {
    const auto ip = 3 * static_cast<Eigen::Index>(p);
    Mdiag_[p] = Gd[p];
    if (m_ > 0) Mdiag_[p] += F_.middleRows(ip, 3) * E_.middleRows(ip, 3).transpose();
    if (p + 1 < uP_) {
      Mnext_[p] = Go[p];
      if (m_ > 0) Mnext_[p] += F_.middleRows(ip, 3) * E_.middleRows(ip + 3, 3).transpose();
    }
  }
}

/// Per group: sum of the redundancy numbers 1 - h and of their squares.
void AdjustmentAnalyser::redundancies(AdjustmentAnalysis& out) const {
  const int G = 2 * S_ + 3;
  out.redundancy.assign(static_cast<std::size_t>(G), 0.0);
  out.redundancy_sq = out.redundancy;
  for (std::size_t i = 0; i < obs_rows_.size(); ++i) {
    const ObsRow& row = obs_rows_[i];
    double h = 0.0;
    for (int a = 0; a < row.nz; ++a)
      for (int b = 0; b < row.nz; ++b) h += row.az[a] * Sinv_(row.cols[a], row.cols[b]) * row.az[b];
    if (row.p >= 0) {
      h += row.ap.dot(Mdiag_[static_cast<std::size_t>(row.p)] * row.ap);
      for (int a = 0; a < row.nz; ++a) h -= 2.0 * row.ap.dot(F_.block(3 * row.p, row.cols[a], 3, 1).col(0)) * row.az[a];
    }
    out.redundancy[static_cast<std::size_t>(obs_group_[i])] += 1.0 - h;
    out.redundancy_sq[static_cast<std::size_t>(obs_group_[i])] += (1.0 - h) * (1.0 - h);
  }
  for (std::size_t i = 0; i < odo_rows_.size(); ++i) {
    const OdoRow& row = odo_rows_[i];
    double h = row.ab.dot(Mdiag_[static_cast<std::size_t>(row.pb)] * row.ab);
    if (row.pa >= 0)
      h += row.aa.dot(Mdiag_[static_cast<std::size_t>(row.pa)] * row.aa) +
           2.0 * row.aa.dot(Mnext_[static_cast<std::size_t>(row.pa)] * row.ab);
    out.redundancy[static_cast<std::size_t>(odo_group_[i])] += 1.0 - h;
    out.redundancy_sq[static_cast<std::size_t>(odo_group_[i])] += (1.0 - h) * (1.0 - h);
  }
}

/// T(g, h) = tr(K_g K_h) for every pair with a process group, in full from X = N^-1 a_i over the
/// 3(K-1) motion rows (see information()).
Eigen::MatrixXd AdjustmentAnalyser::motionTraces() const {
  const int G = 2 * S_ + 3;
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(G, G);
  const Eigen::Index n_motion = static_cast<Eigen::Index>(odo_rows_.size());  // 3P, column c * P + k
  if (n_motion == 0) return T;
  // Motion rows have no landmark or bias part: x_z = -F^T a_y, x_y = D^-1 a_y - E x_z.
  Eigen::MatrixXd Xy = Eigen::MatrixXd::Zero(3 * P_, n_motion), Xz(m_, n_motion);
  for (std::size_t i = 0; i < odo_rows_.size(); ++i) {
    const OdoRow& row = odo_rows_[i];
    const Eigen::Index col = (odo_group_[i] - 2 * S_) * P_ + row.pb;
    Xy.block(3 * row.pb, col, 3, 1) = row.ab;
    if (row.pa >= 0) Xy.block(3 * row.pa, col, 3, 1) = row.aa;
  }
  if (m_ > 0) Xz.noalias() = -F_.transpose() * Xy;
  solveChain(Xy);
  if (m_ > 0) Xy.noalias() -= E_ * Xz;
  // Transposed so that the solution's entries of one unknown are contiguous.
  Xy.transposeInPlace();  // square: no copy
  const Eigen::MatrixXd& XyT = Xy;
  const Eigen::MatrixXd XzT = Xz.transpose();
  Eigen::VectorXd u(n_motion);
  auto accumulate = [&](int g) {
    for (int c = 0; c < 3; ++c) {
      const double t = u.segment(static_cast<Eigen::Index>(c) * P_, P_).squaredNorm();
      T(g, 2 * S_ + c) += t;
      if (g < 2 * S_) T(2 * S_ + c, g) += t;
    }
  };
  for (std::size_t i = 0; i < obs_rows_.size(); ++i) {
    const ObsRow& row = obs_rows_[i];
    u.setZero();
    if (row.p >= 0) u.noalias() += XyT.middleCols(3 * row.p, 3) * row.ap;
    for (int a = 0; a < row.nz; ++a) u.noalias() += row.az[a] * XzT.col(row.cols[a]);
    accumulate(obs_group_[i]);
  }
  for (std::size_t i = 0; i < odo_rows_.size(); ++i) {
    const OdoRow& row = odo_rows_[i];
    u.noalias() = XyT.middleCols(3 * row.pb, 3) * row.ab;
    if (row.pa >= 0) u.noalias() += XyT.middleCols(3 * row.pa, 3) * row.aa;
    accumulate(odo_group_[i]);
  }
  return T;
}

/// REML information of the variance components of the linearised model (Harville 1977,
/// JASA 72(358)), 1/2 tr(P E_g P E_h) with P = W - W A N^-1 A^T W. With whitened rows a_i,
/// K_g = N^-1 N_g and t_g = tr K_g = n_g - r_g it reads
///   I_gh = 1/2 [delta_gh (n_g - 2 t_g) + tr(K_g K_h)] / (var_g var_h),
///   tr(K_g K_h) = sum over rows i of g and j of h of (a_i^T N^-1 a_j)^2.
/// Motion residuals along the chain are strongly correlated (a pose error persists), so
/// every term with a process group is computed in full from X = N^-1 a_i over the 3(K-1)
/// motion rows. Between readings only i = j is kept (sum h_i^2), so a sensor's diagonal is
/// n_g - 2 t_g + sum h_i^2 = sum (1 - h_i)^2 and its terms with other sensors are 0: a reading
/// shares its pose and its landmark with many others, so each cross term is small, and as the
/// terms left out are squares the sensors' information is a lower bound (tests: against the
/// dense form).
void AdjustmentAnalyser::information(AdjustmentAnalysis& out) const {
  const int G = 2 * S_ + 3;
  const Eigen::MatrixXd T = motionTraces();
  std::vector<std::size_t> count(static_cast<std::size_t>(G), 0);
  for (int g : obs_group_) ++count[static_cast<std::size_t>(g)];
  for (int g : odo_group_) ++count[static_cast<std::size_t>(g)];
  out.fisher.resize(G, G);
  for (int g = 0; g < G; ++g)
    for (int h = 0; h < G; ++h) {
      const auto ug = static_cast<std::size_t>(g);
      double v = T(g, h);
      if (g == h && g < 2 * S_) v = out.redundancy_sq[ug];
      else if (g == h) v += static_cast<double>(count[ug]) - 2.0 * (static_cast<double>(count[ug]) - out.redundancy[ug]);
      out.fisher(g, h) = 0.5 * v / (variances_[ug] * variances_[static_cast<std::size_t>(h)]);
    }
}

AdjustmentAnalysis AdjustmentAnalyser::analyse(bool with_information) {
  observationRows();
  odometryRows();
  eliminateChain();
  invertBlocks();
  AdjustmentAnalysis out;
  redundancies(out);
  if (with_information) information(out);
  out.log_det_normal = log_det_;
  out.bias_std.assign(static_cast<std::size_t>(2 * S_), std::numeric_limits<double>::quiet_NaN());
  if (with_biases_)
    for (int s = 0; s < S_; ++s)
      for (int c = 0; c < 2; ++c)
        out.bias_std[static_cast<std::size_t>(2 * s + c)] = std::sqrt(Sinv_(biasCol(s, c), biasCol(s, c)));
  return out;
}

AdjustmentAnalysis analyseAdjustment(const NoiseProblem& problem, const MlState& state,
                                     const std::vector<double>& variances, bool with_biases,
                                     bool with_information = false) {
  return AdjustmentAnalyser(problem, state, variances, with_biases).analyse(with_information);
}


}  // namespace

std::vector<double> groupRedundancy(const NoiseProblem& problem, const MlState& state,
                                    const std::vector<double>& variances, bool with_biases) {
  return analyseAdjustment(problem, state, variances, with_biases).redundancy;
}

Eigen::MatrixXd groupInformation(const NoiseProblem& problem, const MlState& state, const std::vector<double>& variances,
                                 bool with_biases) {
  return analyseAdjustment(problem, state, variances, with_biases, true).fisher;
}

namespace {

/// Checks the configuration against the data: sensor count, translation for the biases.
void checkData(const NoiseProblem& problem, const MlNoiseConfig& config) {
  const int S = problem.sensors;
  if (!config.initial.sensors.empty() && static_cast<int>(config.initial.sensors.size()) != S)
    throw InputError("", "initial noise", "lists " + std::to_string(config.initial.sensors.size()) +
                                              " sensors, the data " + std::to_string(S));
  if (config.estimate_biases) {
    double travel = 0.0;
    for (const auto& u : problem.odometry) travel += std::hypot(u.dx_m, u.dy_m);
    if (!(travel > 0.0))
      throw DataError("odometry", "", "has no translation: sensor biases are not identifiable",
                      "estimate without biases, or record while the robot moves");
  }
}

/// Variances: the initial setting, or 1 (m^2, rad^2) for the sensors and 0.01 for the process:
/// readings start under-weighted against the odometry, which keeps the first adjustment near
/// dead reckoning (over-weighted bearings can pull a landmark onto a pose); zeros start at 0.01.
std::vector<double> initialVariances(int S, const MlNoiseConfig& config) {
  std::vector<double> var(static_cast<std::size_t>(2 * S + 3), 1.0);
  for (int c = 0; c < 3; ++c) var[static_cast<std::size_t>(2 * S + c)] = 0.01;
  if (!config.initial.sensors.empty())
    for (int s = 0; s < S; ++s) {
      var[static_cast<std::size_t>(2 * s)] = config.initial.sensors[static_cast<std::size_t>(s)].range_var_m2;
      var[static_cast<std::size_t>(2 * s + 1)] = config.initial.sensors[static_cast<std::size_t>(s)].bearing_var_rad2;
    }
  const ProcessNoise& q0 = config.initial.process;
  const double q0v[3] = {q0.dx_var_m2, q0.dy_var_m2, q0.dtheta_var_rad2};
  for (int c = 0; c < 3; ++c) {
    double v = q0v[c];
    if (config.estimate_process && !(v > 0.0)) v = 0.01;
    var[static_cast<std::size_t>(2 * S + c)] = std::max(v, config.min_variance);
  }
  return var;
}

ceres::Solver::Options solverOptions(const MlNoiseConfig& config) {
  ceres::Solver::Options sopts;
  sopts.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  sopts.max_num_iterations = config.solver_iterations;
  sopts.num_threads = 1;
  sopts.logging_type = ceres::SILENT;
  sopts.minimizer_progress_to_stdout = false;
  sopts.function_tolerance = 1e-10;
  sopts.gradient_tolerance = 1e-10;
  sopts.parameter_tolerance = 1e-10;
  return sopts;
}

ceres::Problem::Options problemOptions() {
  ceres::Problem::Options popts;
  popts.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  return popts;
}

/// Iterated variance-component estimation (the steps of ml.hpp): the weighted adjustment
/// (Ceres, whitened by the current variances), then per group the Foerstner update as a
/// scoring step, until the variances settle; then the standard errors.
class VceEstimator {
 public:
  VceEstimator(const NoiseProblem& problem, const MlNoiseConfig& config);
  MlNoiseResult run();

 private:
  /// A process variance is held at its start when the process noise is given.
  bool fixedGroup(int g) const { return g >= 2 * S_ && !config_.estimate_process; }
  void setWeights();
  void buildAdjustment();
  void solve(bool wrap_yaw);
  void checkLandmarksOffRobot() const;
  bool updateVariances();
  double updatedVariance(int g, double r, double r2, double omega);
  void fillNoise();
  void standardErrors(const AdjustmentAnalysis& an);

  const NoiseProblem& problem_;
  const MlNoiseConfig& config_;
  const int S_, K_, G_;
  std::vector<double> var_;                         // current variances, order of the groups
  std::vector<double> inv_sigma_;                   // 1 / sqrt(var), read by the cost functions
  MlNoiseResult result_;
  std::vector<std::array<double, 3>> pose_blocks_;  // Ceres parameter blocks of the poses
  ceres::Problem cp_;
  const ceres::Solver::Options sopts_;
  const std::vector<std::string> names_;
  std::vector<double> acceleration_, last_step_;    // per group: scoring step factor, last step
};

VceEstimator::VceEstimator(const NoiseProblem& problem, const MlNoiseConfig& config)
    : problem_(problem),
      config_(config),
      S_(problem.sensors),
      K_(problem.stops),
      G_(2 * S_ + 3),
      var_(initialVariances(S_, config)),
      inv_sigma_(static_cast<std::size_t>(G_)),
      pose_blocks_(static_cast<std::size_t>(K_)),
      cp_(problemOptions()),
      sopts_(solverOptions(config)),
      names_(groupNames(S_)),
      acceleration_(static_cast<std::size_t>(G_), 1.0),
      last_step_(static_cast<std::size_t>(G_), 0.0) {}

void VceEstimator::setWeights() {
  for (int g = 0; g < G_; ++g) inv_sigma_[static_cast<std::size_t>(g)] = 1.0 / std::sqrt(var_[static_cast<std::size_t>(g)]);
}

void VceEstimator::buildAdjustment() {
  result_.state = initialState(problem_);
  MlState& st = result_.state;
  for (int k = 0; k < K_; ++k) {
    const Pose2& p = st.poses[static_cast<std::size_t>(k)];
    pose_blocks_[static_cast<std::size_t>(k)] = {p.x_m, p.y_m, p.yaw_rad};
  }
  for (const auto& o : problem_.observations) {
    const double* w = &inv_sigma_[static_cast<std::size_t>(2 * o.sensor)];
    double* lm = st.landmarks[static_cast<std::size_t>(o.landmark)].data();
    double* bias = st.biases[static_cast<std::size_t>(o.sensor)].data();
    if (o.stop == 0)
      cp_.AddResidualBlock(new ObservationCost(o, false, w), nullptr, lm, bias);
    else
      cp_.AddResidualBlock(new ObservationCost(o, true, w), nullptr, pose_blocks_[static_cast<std::size_t>(o.stop)].data(), lm, bias);
  }
  for (int k = 1; k < K_; ++k) {
    const double* w = &inv_sigma_[static_cast<std::size_t>(2 * S_)];
    const OdometryStep& u = problem_.odometry[static_cast<std::size_t>(k)];
    if (k == 1)
      cp_.AddResidualBlock(new OdometryCost(u, true, w), nullptr, pose_blocks_[1].data());
    else
      cp_.AddResidualBlock(new OdometryCost(u, false, w), nullptr, pose_blocks_[static_cast<std::size_t>(k - 1)].data(),
                           pose_blocks_[static_cast<std::size_t>(k)].data());
  }
  if (!config_.estimate_biases)
    for (auto& b : st.biases) cp_.SetParameterBlockConstant(b.data());
}

/// One weighted adjustment; the poses copied back (yaw wrapped for the final one).
void VceEstimator::solve(bool wrap_yaw) {
  ceres::Solver::Summary summary;
  ceres::Solve(sopts_, &cp_, &summary);
  result_.solver_iterations += static_cast<int>(summary.iterations.size());
  for (int k = 0; k < K_; ++k) {
    const auto& b = pose_blocks_[static_cast<std::size_t>(k)];
    result_.state.poses[static_cast<std::size_t>(k)] = Pose2{b[0], b[1], wrap_yaw ? wrapAngle(b[2]) : b[2]};
  }
}

/// A landmark on top of a pose has no bearing and a singular Jacobian: the data hold a
/// reading at (nearly) zero range, which the Gaussian model cannot explain.
void VceEstimator::checkLandmarksOffRobot() const {
  const MlState& st = result_.state;
  for (const auto& o : problem_.observations) {
    const auto& l = st.landmarks[static_cast<std::size_t>(o.landmark)];
    const Pose2& p = st.poses[static_cast<std::size_t>(o.stop)];
    if (std::hypot(l[0] - p.x_m, l[1] - p.y_m) < 1e-4)
      throw DataError("observations", "stop " + std::to_string(o.stop) + ", landmark " + std::to_string(problem_.landmark_ids[static_cast<std::size_t>(o.landmark)]),
                      "the adjustment put the landmark on the robot (reading range " + std::to_string(o.range_m) + " m)",
                      "leave out readings at ranges the sensor cannot measure (below its minimum range)");
  }
}

/// Foerstner's update var <- Omega / r is a fixed-point step of the REML score
/// (Omega / var - r) / (2 var) = 0; scaling it by the diagonal Fisher information
/// sum r_ii^2 / (2 var^2) gives a scoring step that reaches a component near zero in a
/// few iterations instead of ~1/n. Safeguard: at most a factor 10 per iteration.
/// The diagonal information ignores correlations between residuals, so the step can
/// overshoot: the extra factor is halved each time the step changes sign.
double VceEstimator::updatedVariance(int g, double r, double r2, double omega) {
  const auto ug = static_cast<std::size_t>(g);
  const double em_step = omega / r - var_[ug];
  if (em_step * last_step_[ug] < 0.0) acceleration_[ug] *= 0.5;
  const double factor = 1.0 + acceleration_[ug] * (r * r / r2 / r - 1.0);
  const double ratio = std::clamp((var_[ug] + factor * em_step) / var_[ug], 0.1, 10.0);
  last_step_[ug] = em_step;
  return std::max(var_[ug] * ratio, config_.min_variance);
}

/// Variance components from the residuals and the redundancy numbers; true when converged.
bool VceEstimator::updateVariances() {
  std::vector<int> group_of;
  const std::vector<double> res = residualsAt(problem_, result_.state, &group_of);
  std::vector<double> omega(static_cast<std::size_t>(G_), 0.0);
  std::vector<std::size_t> count(static_cast<std::size_t>(G_), 0);
  for (std::size_t i = 0; i < res.size(); ++i) {
    omega[static_cast<std::size_t>(group_of[i])] += res[i] * res[i];
    ++count[static_cast<std::size_t>(group_of[i])];
  }
  const AdjustmentAnalysis an = analyseAdjustment(problem_, result_.state, var_, config_.estimate_biases);
  // Restricted (REML) negative log-likelihood of the linearised model, constants dropped:
  //   1/2 [ sum_g n_g log var_g + sum_g Omega_g / var_g + log det N ].
  double nll = 0.5 * an.log_det_normal;
  bool converged = true;
  for (int g = 0; g < G_; ++g) {
    const auto ug = static_cast<std::size_t>(g);
    MlGroup& grp = result_.groups[ug];
    grp.name = names_[ug];
    grp.count = count[ug];
    grp.redundancy = an.redundancy[ug];
    grp.sum_sq = omega[ug];
    if (count[ug] > 0) nll += 0.5 * (omega[ug] / var_[ug] + static_cast<double>(count[ug]) * std::log(var_[ug]));
    const double r = an.redundancy[ug], r2 = an.redundancy_sq[ug];
    double updated = var_[ug];
    if (!fixedGroup(g) && count[ug] > 0 && r > 1e-12 && r2 > 1e-24) updated = updatedVariance(g, r, r2, omega[ug]);
    const double se = updated * std::sqrt(2.0 / std::max(r2, 1e-24));
    // Converged when the change is small against the variance or, for components near zero,
    // against their standard error (the likelihood is flat there).
    if (std::abs(updated - var_[ug]) > config_.tolerance * std::max(updated, se)) converged = false;
    grp.variance = updated;
    grp.standard_error = se;
    grp.at_floor = updated <= config_.min_variance;
    var_[ug] = updated;
  }
  result_.objective_trace.push_back(nll);
  result_.variance_trace.push_back(var_);
  return converged;
}

void VceEstimator::fillNoise() {
  const MlState& st = result_.state;
  result_.noise.sensors.resize(static_cast<std::size_t>(S_));
  for (int s = 0; s < S_; ++s) {
    SensorNoise& n = result_.noise.sensors[static_cast<std::size_t>(s)];
    n.range_mean_m = st.biases[static_cast<std::size_t>(s)][0];
    n.bearing_mean_rad = st.biases[static_cast<std::size_t>(s)][1];
    n.range_var_m2 = var_[static_cast<std::size_t>(2 * s)];
    n.bearing_var_rad2 = var_[static_cast<std::size_t>(2 * s + 1)];
  }
  result_.noise.process.dx_var_m2 = var_[static_cast<std::size_t>(2 * S_)];
  result_.noise.process.dy_var_m2 = var_[static_cast<std::size_t>(2 * S_ + 1)];
  result_.noise.process.dtheta_var_rad2 = var_[static_cast<std::size_t>(2 * S_ + 2)];
}

/// Standard errors from the inverse information over the variances that were estimated and
/// are away from the floor (fixed ones and those at the floor are held as known).
void VceEstimator::standardErrors(const AdjustmentAnalysis& an) {
  std::vector<int> free;
  for (int g = 0; g < G_; ++g) {
    const MlGroup& grp = result_.groups[static_cast<std::size_t>(g)];
    if (!fixedGroup(g) && grp.count > 0 && !grp.at_floor) free.push_back(g);
  }
  const auto n_free = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd info(n_free, n_free);
  for (Eigen::Index a = 0; a < n_free; ++a)
    for (Eigen::Index b = 0; b < n_free; ++b)
      info(a, b) = an.fisher(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(b)]);
  Eigen::LLT<Eigen::MatrixXd> llt(info);
  if (n_free > 0 && llt.info() == Eigen::Success) {
    const Eigen::MatrixXd cov = llt.solve(Eigen::MatrixXd::Identity(n_free, n_free));
    for (Eigen::Index a = 0; a < n_free; ++a)
      result_.groups[static_cast<std::size_t>(free[static_cast<std::size_t>(a)])].standard_error = std::sqrt(cov(a, a));
    result_.standard_error_method = "information";
  }
}

MlNoiseResult VceEstimator::run() {
  setWeights();
  buildAdjustment();
  result_.groups.resize(static_cast<std::size_t>(G_));
  for (int it = 0; it < config_.max_iterations; ++it) {
    setWeights();
    solve(false);
    ++result_.iterations;
    checkLandmarksOffRobot();
    if (updateVariances()) {
      result_.converged = true;
      break;
    }
  }
  if (!result_.converged)
    result_.message = "variances still changing after " + std::to_string(config_.max_iterations) + " iterations";
  // Final solve at the final variances so poses, landmarks and biases match them.
  setWeights();
  solve(true);
  fillNoise();
  const bool full_information = K_ - 1 <= config_.max_motions_for_information;
  const AdjustmentAnalysis an = analyseAdjustment(problem_, result_.state, var_, config_.estimate_biases, full_information);
  result_.bias_standard_error = an.bias_std;
  if (full_information) standardErrors(an);
  return std::move(result_);
}

}  // namespace

MlNoiseResult estimateNoiseMl(const NoiseProblem& problem, const MlNoiseConfig& config) {
  config.validate();
  checkData(problem, config);
  return VceEstimator(problem, config).run();
}

}  // namespace lidarcal::noise
