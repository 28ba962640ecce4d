// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/oracle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "calibration/closed_form_stage.hpp"
#include "calibration/inversion.hpp"
#include "calibration/noise_fits.hpp"
#include "common/information_criteria.hpp"

namespace lidarcal::calibration {

CalibrationModel calibrateAgainstTruth(const std::vector<RangePair>& pairs,
                                       const CalibrationConfig& config,
                                       const std::vector<std::vector<double>>& batches,
                                       double range_min_m, double range_max_m) {
  config.validate();
  CalibrationModel m;
  m.method = "oracle";
  m.model.range_min_m = range_min_m;
  m.model.range_max_m = range_max_m;
  if (pairs.size() < static_cast<std::size_t>(config.max_order) + 3) {
    m.status.code = StatusCode::too_few_observations;
    m.status.message = "too few readings with a known distance";
    return m;
  }
  const Admissible window =
      range_max_m < 1e8 ? invertibleOver(range_min_m, range_max_m) : Admissible{};
  const OrderSelection sel = selectOrder(pairs, config.max_order, config.closed_form_rule, window);
  fillOrders(m, sel, pairs.size());
  std::vector<double> d, y;
  for (const auto& p : pairs) {
    d.push_back(p.d_m);
    y.push_back(p.y_m);
  }
  int order = std::max(sel.chosen, 1);
  if (config.noise == NoiseKind::squared) {
    // With known distances the oracle is Alhashimi et al. 2016's estimator: full ML of model (1)
    // for every order (eqs. 18-20, from the closed form eqs. 21-26) and the order by AIC on that
    // likelihood.
    double best = std::numeric_limits<double>::infinity();
    for (auto& row : m.orders) {
      if (row.order < 1) continue;
      const Alhashimi2016Fit cf = fitAlhashimi2016ClosedForm(d, y, row.order);
      const Alhashimi2016Fit ml = fitAlhashimi2016ML(d, y, cf.alpha);
      const double k = row.order + 2.0;
      row.alpha = ml.alpha;
      row.aic = akaike(k, ml.neg_log_likelihood);
      row.bic = schwarz(k, d.size(), ml.neg_log_likelihood);
      row.invertible = !window || window(row.alpha);
      if (row.invertible && row.aic < best) {
        best = row.aic;
        order = row.order;
      }
    }
    m.order_aic = order;
    m.order_rule = "aic (Alhashimi et al. 2016 ML)";
    m.model.bias.alpha = m.orders[static_cast<std::size_t>(order)].alpha;
  } else {
    m.model.bias.alpha = sel.table[static_cast<std::size_t>(std::min<int>(
                                       order, static_cast<int>(sel.table.size()) - 1))]
                             .alpha;
  }
  fillNoiseFits(m, order, d, y, batches, config.threads);
  m.model.noise = fitNoiseLaw(config.noise, order, m.model.bias, d, y);
  m.residual_rms_m = rmsResidual(m.model.bias, d, y);
  m.readings = d.size();
  m.fitted_range_m = fittedRange(d, y, m.model.bias);
  return m;
}

}  // namespace lidarcal::calibration
