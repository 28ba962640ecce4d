// SPDX-License-Identifier: BSD-3-Clause
// The normal matrix of the ML noise adjustment and what it gives: redundancy numbers per group,
// log det N, the biases' standard errors, the REML information of the variances.
#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "common/errors.hpp"
#include "noise/ml_model.hpp"

namespace lidarcal::noise {
namespace ml {
namespace {

/// One whitened observation row: pose part (3, when the stop is not 0) and z part (indices,
/// values).
struct ObsRow {
  int p;  // pose index (stop - 1) or -1
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
  AdjustmentAnalyser(const NoiseProblem& problem, const MlState& state,
                     const std::vector<double>& variances, bool with_biases);
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
  std::vector<Mat3> Dd_, Do_;  // D: diagonal and first off-diagonal pose blocks
  Eigen::MatrixXd B_, C_;      // N_yz, N_zz
  std::vector<ObsRow> obs_rows_;
  std::vector<int> obs_group_;
  std::vector<OdoRow> odo_rows_;
  std::vector<int> odo_group_;
  std::vector<Mat3> Pinv_;           // inverses of the pose Schur blocks (forward elimination)
  double log_det_ = 0.0;             // log det N = sum log det(pose Schur blocks) + log det S
  Eigen::MatrixXd E_, Sinv_, F_;     // D^-1 B, S^-1, E S^-1
  std::vector<Mat3> Mdiag_, Mnext_;  // (N^-1) blocks of a pose with itself and with the next pose
};

AdjustmentAnalyser::AdjustmentAnalyser(const NoiseProblem& problem, const MlState& state,
                                       const std::vector<double>& variances, bool with_biases)
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
    linearizeObservation(state_.poses[static_cast<std::size_t>(o.stop)],
                         state_.landmarks[static_cast<std::size_t>(o.landmark)].data(),
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
        for (int i = 0; i < row.nz; ++i)
          B_.block(3 * row.p, row.cols[i], 3, 1) += row.ap * row.az[i];
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
    linearizeOdometry(state_.poses[static_cast<std::size_t>(k - 1)],
                      state_.poses[static_cast<std::size_t>(k)],
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
  for (Eigen::Index i = 0; i < llt.matrixLLT().rows(); ++i)
    log_det += 2.0 * std::log(llt.matrixLLT()(i, i));
}

/// Block-tridiagonal elimination of the pose chain (forward).
void AdjustmentAnalyser::eliminateChain() {
  Pinv_.resize(uP_);
  for (std::size_t p = 0; p < uP_; ++p) {
    Mat3 schur = Dd_[p];
    if (p > 0) schur -= Do_[p - 1].transpose() * Pinv_[p - 1] * Do_[p - 1];
    Eigen::LLT<Mat3> llt(schur);
    if (llt.info() != Eigen::Success)
      throw DataError("", "pose " + std::to_string(p + 1),
                      "is not determined by the data (singular normal matrix)",
                      "check the odometry and that every stop is connected to the previous one");
    addLogDet(llt, log_det_);
    Pinv_[p] = llt.solve(Mat3::Identity());
  }
}

/// M <- D^-1 M for a 3P-row matrix: forward elimination, then back substitution.
void AdjustmentAnalyser::solveChain(Eigen::MatrixXd& M) const {
  for (std::size_t p = 1; p < uP_; ++p)
    M.middleRows(3 * static_cast<Eigen::Index>(p), 3) -=
        Do_[p - 1].transpose() * Pinv_[p - 1] *
        M.middleRows(3 * static_cast<Eigen::Index>(p - 1), 3);
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
      throw DataError(
          "", "landmarks and biases", "are not determined by the data (singular normal matrix)",
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
      for (int a = 0; a < row.nz; ++a)
        h -= 2.0 * row.ap.dot(F_.block(3 * row.p, row.cols[a], 3, 1).col(0)) * row.az[a];
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
  // 3P, column c * P + k
  const Eigen::Index n_motion = static_cast<Eigen::Index>(odo_rows_.size());
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
      if (g == h && g < 2 * S_)
        v = out.redundancy_sq[ug];
      else if (g == h)
        v += static_cast<double>(count[ug]) -
             2.0 * (static_cast<double>(count[ug]) - out.redundancy[ug]);
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
        out.bias_std[static_cast<std::size_t>(2 * s + c)] =
            std::sqrt(Sinv_(biasCol(s, c), biasCol(s, c)));
  return out;
}

}  // namespace

AdjustmentAnalysis analyseAdjustment(const NoiseProblem& problem, const MlState& state,
                                     const std::vector<double>& variances, bool with_biases,
                                     bool with_information) {
  return AdjustmentAnalyser(problem, state, variances, with_biases).analyse(with_information);
}

}  // namespace ml

std::vector<double> groupRedundancy(const NoiseProblem& problem, const MlState& state,
                                    const std::vector<double>& variances, bool with_biases) {
  return ml::analyseAdjustment(problem, state, variances, with_biases).redundancy;
}

Eigen::MatrixXd groupInformation(const NoiseProblem& problem, const MlState& state,
                                 const std::vector<double>& variances, bool with_biases) {
  return ml::analyseAdjustment(problem, state, variances, with_biases, true).fisher;
}

}  // namespace lidarcal::noise
