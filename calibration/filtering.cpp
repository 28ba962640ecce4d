// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/filtering.hpp"
#include "calibration/discrepancy.hpp"
#include "common/stats_util.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <optional>

namespace lidarcal::calibration {

const char* toString(Outside o) {
  switch (o) {
    case Outside::linear:
      return "linear";
    case Outside::keep:
      return "keep";
    case Outside::extrapolate:
      return "extrapolate";
    case Outside::drop:
      return "drop";
  }
  return "?";
}

namespace {
constexpr Outside kAllOutside[] = {Outside::linear, Outside::keep, Outside::extrapolate,
                                   Outside::drop};
}  // namespace

bool parseOutside(const std::string& name, Outside& out) {
  for (Outside o : kAllOutside)
    if (name == toString(o)) {
      out = o;
      return true;
    }
  return false;
}

std::vector<std::string> outsidePolicies() {
  std::vector<std::string> names;
  for (Outside o : kAllOutside) names.emplace_back(toString(o));
  return names;
}

std::string outsideNames() {
  std::string s;
  for (std::size_t i = 0; i < std::size(kAllOutside); ++i)
    s += std::string(i == 0                            ? ""
                     : i + 1 == std::size(kAllOutside) ? " or "
                                                       : ", ") +
         toString(kAllOutside[i]);
  return s;
}

CorrectionWindow correctionWindow(const CalibrationModel& model, Outside outside) {
  CorrectionWindow w;
  w.outside = outside;
  if (model.fitted_range_m) {
    const auto [lo, hi] = *model.fitted_range_m;
    const BiasPolynomial& f = model.model.bias;
    w.distance_min_m = lo;
    w.distance_max_m = hi;
    w.reading_min_m = f(lo);
    w.reading_max_m = f(hi);
    w.slope_min = f.derivative(lo);
    w.slope_max = f.derivative(hi);
  }
  return w;
}

RangeInverter modelInverter(const CalibrationModel& model, InversionMethod method,
                            Outside outside) {
  InversionConfig c = inversionWindow(model.model, method);
  if (model.fitted_range_m && outside != Outside::extrapolate) {
    const auto [lo, hi] = *model.fitted_range_m;
    const double margin = 0.05 * (hi - lo);
    c.d_min_m = std::max(0.0, lo - margin);
    c.d_max_m = hi + margin;
  }
  return RangeInverter(model.model, c);
}

CorrectedReading ReadingCorrector::operator()(double r) const {
  const CorrectionWindow& w = window;
  const bool below = r<w.reading_min_m, above = r> w.reading_max_m;
  if ((below || above) && w.outside == Outside::keep)
    return {r, ReadingFate::outside_kept, kNaN, kNaN};
  if ((below || above) && w.outside == Outside::drop)
    return {kNaN, ReadingFate::outside_dropped, kNaN, kNaN};
  if (!(r > 0.0)) return {kNaN, ReadingFate::unresolved, kNaN, kNaN};
  std::optional<double> d;
  if ((below || above) && w.outside == Outside::linear) {
    const double slope = above ? w.slope_max : w.slope_min;
    const double edge_d = above ? w.distance_max_m : w.distance_min_m;
    const double edge_y = above ? w.reading_max_m : w.reading_min_m;
    if (slope > 0.0) d = edge_d + (r - edge_y) / slope;
    if (d && !(*d > 0.0)) d.reset();
  } else {
    d = inverter.invert(r);
  }
  if (!d) return {kNaN, ReadingFate::unresolved, kNaN, kNaN};
  const CorrectionErrors e = errorsAt(*d);
  return {*d, below || above ? ReadingFate::extrapolated : ReadingFate::corrected, e.predictive_m,
          e.curve_m};
}

CorrectionErrors ReadingCorrector::errorsAt(double d) const {
  // The polynomial's own extrapolation has the polynomial's own uncertainty: no clamp to the edge.
  const bool own = window.outside == Outside::extrapolate;
  const double lo = own ? d : window.distance_min_m, hi = own ? d : window.distance_max_m;
  const double curve = correctionStandardError(bias, covariance, d, lo, hi);
  // The discrepancy is in reading units: through the slope of the rule that corrected the reading.
  const double slope = bias.derivative(std::clamp(d, lo, hi));
  const double predictive =
      slope > 0.0 ? predictiveStandardError(curve * slope, discrepancy) / slope : kNaN;
  return {predictive, curve};
}

ReadingCorrector readingCorrector(const CalibrationModel& model, InversionMethod method,
                                  Outside outside) {
  return {modelInverter(model, method, outside), correctionWindow(model, outside), model.model.bias,
          model.alpha_covariance, model.discrepancy};
}

void FilteringStats::add(const CorrectedReading& c, double reading_m, bool below_window) {
  switch (c.fate) {
    case ReadingFate::corrected:
      ++corrected;
      return;
    case ReadingFate::unresolved:
      ++unresolved;
      return;
    case ReadingFate::extrapolated:
      ++extrapolated;
      break;
    case ReadingFate::outside_kept:
    case ReadingFate::outside_dropped:
      ++outside;
      break;
  }
  if (below_window) {
    ++below;
    beyond_min_m = std::min(beyond_min_m, reading_m);
  } else {
    beyond_max_m = std::max(beyond_max_m, reading_m);
  }
}

FilteringStats& FilteringStats::operator+=(const FilteringStats& o) {
  points += o.points;
  corrected += o.corrected;
  extrapolated += o.extrapolated;
  unresolved += o.unresolved;
  outside += o.outside;
  below += o.below;
  beyond_min_m = std::min(beyond_min_m, o.beyond_min_m);
  beyond_max_m = std::max(beyond_max_m, o.beyond_max_m);
  return *this;
}

io::Scan correctScan(const io::Scan& scan, const ReadingCorrector& correct, FilteringStats* stats) {
  io::Scan out;
  out.name = scan.name;
  out.viewpoint = scan.viewpoint;
  out.has_intensity = scan.has_intensity;
  out.labels = scan.labels;
  // A deliberate copy: the corrected scan is a new output; the input stays as read.
  out.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>(*scan.cloud));
  out.correction.assign(out.cloud->size(), io::PointCorrection::no_return);
  out.correction_se.assign(out.cloud->size(), std::numeric_limits<float>::quiet_NaN());
  FilteringStats s;
  s.points = out.cloud->size();
  constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < out.cloud->size(); ++i) {
    auto& p = (*out.cloud)[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    const double r = std::hypot(static_cast<double>(p.x), static_cast<double>(p.y));
    const CorrectedReading c = correct(r);
    s.add(c, r, r < correct.window.reading_min_m);
    switch (c.fate) {
      case ReadingFate::outside_kept:
        out.correction[i] = io::PointCorrection::raw;
        continue;
      case ReadingFate::outside_dropped:
      case ReadingFate::unresolved:
        break;
      case ReadingFate::corrected:
      case ReadingFate::extrapolated: {
        const double k = c.range_m / r;  // move the point along its beam
        p.x = static_cast<float>(p.x * k);
        p.y = static_cast<float>(p.y * k);
        const bool inside = c.fate == ReadingFate::corrected;
        out.correction[i] =
            inside ? io::PointCorrection::corrected : io::PointCorrection::extrapolated;
        out.correction_se[i] = static_cast<float>(c.standard_error_m);
        continue;
      }
    }
    p.x = p.y = p.z = kNaNf;  // dropped or unresolved: a beam without return
    out.cloud->is_dense = false;
  }
  if (stats) *stats = s;
  return out;
}

}  // namespace lidarcal::calibration
