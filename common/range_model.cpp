// SPDX-License-Identifier: BSD-3-Clause
#include "common/range_model.hpp"

#include <cmath>

namespace lidarcal {

double BiasPolynomial::operator()(double d_m) const {
  double value = 0.0;
  for (auto it = alpha.rbegin(); it != alpha.rend(); ++it) value = value * d_m + *it;
  return value;
}

double BiasPolynomial::derivative(double d_m) const {
  double value = 0.0;
  for (std::size_t i = alpha.size(); i-- > 1;)
    value = value * d_m + static_cast<double>(i) * alpha[i];
  return value;
}

double NoiseModel::stddev(double d_m, const BiasPolynomial& f) const {
  switch (kind) {
    case NoiseKind::none:
      return 0.0;
    case NoiseKind::constant:
      return sigma_e;
    case NoiseKind::polynomial: {
      double value = 0.0;
      for (auto it = beta.rbegin(); it != beta.rend(); ++it) value = value * d_m + *it;
      return std::abs(value);
    }
    case NoiseKind::squared: {
      const double fd = f(d_m);
      return sigma_e * fd * fd;
    }
    case NoiseKind::power:
      return sigma_e * std::pow(std::abs(f(d_m)), exponent);
  }
  return 0.0;
}

const char* toString(NoiseKind kind) {
  switch (kind) {
    case NoiseKind::none:
      return "none";
    case NoiseKind::constant:
      return "constant";
    case NoiseKind::polynomial:
      return "polynomial";
    case NoiseKind::squared:
      return "squared";
    case NoiseKind::power:
      return "power";
  }
  return "unknown";
}

bool parseNoiseKind(const std::string& name, NoiseKind& kind) {
  for (NoiseKind k : {NoiseKind::none, NoiseKind::constant, NoiseKind::polynomial,
                      NoiseKind::squared, NoiseKind::power}) {
    if (name == toString(k)) {
      kind = k;
      return true;
    }
  }
  return false;
}

}  // namespace lidarcal
