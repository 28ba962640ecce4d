// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A covariance as a command's JSON output writes it: the parameters' names in order and the
// matrix as rows.

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace lidarcal::pipeline {

template <typename Names, typename Derived>
nlohmann::json covarianceJson(const Names& order, const Eigen::MatrixBase<Derived>& covariance) {
  nlohmann::json matrix = nlohmann::json::array();
  for (Eigen::Index a = 0; a < covariance.rows(); ++a) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index b = 0; b < covariance.cols(); ++b) row.push_back(covariance(a, b));
    matrix.push_back(row);
  }
  return {{"order", order}, {"matrix", matrix}};
}

}  // namespace lidarcal::pipeline
