// SPDX-License-Identifier: BSD-3-Clause
#include "io/raw_scan_cloud.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace lidarcal::io {

CloudCounts toCloud(const RawScan& raw, pcl::PointCloud<pcl::PointXYZI>& cloud) {
  if (raw.angles_rad.size() != raw.ranges_m.size())
    throw std::invalid_argument("toCloud: angles and ranges differ in number");
  const bool has_intensity = !raw.intensities.empty();
  if (has_intensity && raw.intensities.size() != raw.ranges_m.size())
    throw std::invalid_argument("toCloud: intensities and ranges differ in number");
  const std::size_t n = raw.ranges_m.size();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  CloudCounts counts;
  cloud.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double r = raw.ranges_m[i];
    pcl::PointXYZI& p = cloud[i];
    p.intensity = has_intensity ? raw.intensities[i] : 0.0f;
    if (!std::isfinite(r) || r <= 0.0) {
      ++counts.no_return;
      p.x = p.y = p.z = nan;
    } else if (r < raw.range_min_m || r > raw.range_max_m) {
      ++counts.outside_limits;
      p.x = p.y = p.z = nan;
    } else {
      ++counts.returns;
      p.x = static_cast<float>(r * std::cos(raw.angles_rad[i]));
      p.y = static_cast<float>(r * std::sin(raw.angles_rad[i]));
      p.z = 0.0f;
    }
  }
  return counts;
}

RawScan toRawScan(const Scan& scan, double range_min_m, double range_max_m) {
  RawScan raw;
  raw.pose = scan.viewpoint;
  raw.range_min_m = range_min_m;
  raw.range_max_m = range_max_m;
  const auto& cloud = *scan.cloud;
  raw.angles_rad.reserve(cloud.size());
  raw.ranges_m.reserve(cloud.size());
  if (scan.has_intensity) raw.intensities.reserve(cloud.size());
  for (const auto& p : cloud) {
    const bool hit = std::isfinite(p.x) && std::isfinite(p.y);
    raw.angles_rad.push_back(hit ? std::atan2(static_cast<double>(p.y), static_cast<double>(p.x))
                                 : 0.0);
    raw.ranges_m.push_back(hit ? std::hypot(p.x, p.y) : std::numeric_limits<float>::quiet_NaN());
    if (scan.has_intensity) raw.intensities.push_back(p.intensity);
  }
  return raw;
}

}  // namespace lidarcal::io
