#include "calibration/filtering.hpp"

#include <cmath>
#include <limits>

namespace lidarcal::calibration {

io::Scan correctScan(const io::Scan& scan, const RangeInverter& inverter, FilteringStats* stats) {
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
    const auto d = inverter.invert(r);
    if (!d || !(r > 0.0)) {
      p.x = p.y = p.z = kNaN;
      out.cloud->is_dense = false;
      ++s.unresolved;
      continue;
    }
    const double k = *d / r;  // move the point along its beam
    p.x = static_cast<float>(p.x * k);
    p.y = static_cast<float>(p.y * k);
    ++s.corrected;
  }
  if (stats) *stats = s;
  return out;
}

}  // namespace lidarcal::calibration
