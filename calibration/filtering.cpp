#include "calibration/filtering.hpp"
#include "common/stats_util.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lidarcal::calibration {

const char* toString(Outside o) {
  switch (o) {
    case Outside::keep: return "keep";
    case Outside::extrapolate: return "extrapolate";
    case Outside::drop: return "drop";
  }
  return "?";
}

bool parseOutside(const std::string& name, Outside& out) {
  for (Outside o : {Outside::keep, Outside::extrapolate, Outside::drop})
    if (name == toString(o)) {
      out = o;
      return true;
    }
  return false;
}

CorrectionWindow correctionWindow(const CalibrationModel& model, Outside outside) {
  CorrectionWindow w;
  w.outside = outside;
  if (model.fitted_range_m && outside != Outside::extrapolate) {
    w.reading_min_m = model.model.bias(model.fitted_range_m->first);
    w.reading_max_m = model.model.bias(model.fitted_range_m->second);
  }
  return w;
}

RangeInverter modelInverter(const CalibrationModel& model, InversionMethod method, Outside outside) {
  InversionConfig c = inversionWindow(model.model, method);
  if (model.fitted_range_m && outside != Outside::extrapolate) {
    const auto [lo, hi] = *model.fitted_range_m;
    const double margin = 0.05 * (hi - lo);
    c.d_min_m = std::max(0.0, lo - margin);
    c.d_max_m = hi + margin;
  }
  return RangeInverter(model.model, c);
}

CorrectedReading correctReading(double r, const RangeInverter& inverter, const CorrectionWindow& window) {
  if ((r < window.reading_min_m || r > window.reading_max_m) && window.outside != Outside::extrapolate) {
    if (window.outside == Outside::drop) return {kNaN, ReadingFate::outside_dropped};
    return {r, ReadingFate::outside_kept};
  }
  const auto d = inverter.invert(r);
  if (!d || !(r > 0.0)) return {kNaN, ReadingFate::unresolved};
  return {*d, ReadingFate::corrected};
}

ReadingCorrector readingCorrector(const CalibrationModel& model, InversionMethod method, Outside outside) {
  return {modelInverter(model, method, outside), correctionWindow(model, outside)};
}

io::Scan correctScan(const io::Scan& scan, const RangeInverter& inverter, FilteringStats* stats,
                     const CorrectionWindow& window) {
  io::Scan out;
  out.name = scan.name;
  out.viewpoint = scan.viewpoint;
  out.has_intensity = scan.has_intensity;
  out.labels = scan.labels;
  // A deliberate copy: the corrected scan is a new output; the input stays as read.
  out.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>(*scan.cloud));
  FilteringStats s;
  s.points = out.cloud->size();
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  for (auto& p : *out.cloud) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    const double r = std::hypot(static_cast<double>(p.x), static_cast<double>(p.y));
    const CorrectedReading c = correctReading(r, inverter, window);
    switch (c.fate) {
      case ReadingFate::outside_kept: ++s.outside; continue;
      case ReadingFate::outside_dropped: ++s.outside; break;
      case ReadingFate::unresolved: ++s.unresolved; break;
      case ReadingFate::corrected: {
        const double k = c.range_m / r;  // move the point along its beam
        p.x = static_cast<float>(p.x * k);
        p.y = static_cast<float>(p.y * k);
        ++s.corrected;
        continue;
      }
    }
    p.x = p.y = p.z = kNaN;  // dropped or unresolved: a beam without return
    out.cloud->is_dense = false;
  }
  if (stats) *stats = s;
  return out;
}

}  // namespace lidarcal::calibration
