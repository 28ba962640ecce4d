// SPDX-License-Identifier: BSD-3-Clause
#include "io/sequence_writer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/errors.hpp"
#include "io/raw_scan_cloud.hpp"
#include "io/sequence.hpp"

namespace lidarcal::io {

namespace {
SequenceWriterConfig validated(const SequenceWriterConfig& config) {
  config.validate();
  return config;
}
}  // namespace

void SequenceWriterConfig::validate() const {
  if (every < 1) throw InputError("", "--every", "must be at least 1", "use 1 to keep every scan");
}

SequenceWriter::SequenceWriter(const std::filesystem::path& out, const SequenceWriterConfig& config)
    : config_(validated(config)), dir_(out, config.overwrite) {
  summary_.out = dir_.target();
  summary_.range_min_m = std::numeric_limits<double>::infinity();
  summary_.range_max_m = -std::numeric_limits<double>::infinity();
  scratch_.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
}

bool SequenceWriter::add(const RawScan& raw) {
  if (config_.max_scans != 0 && summary_.written >= config_.max_scans) return false;
  const std::size_t index = summary_.offered++;
  if (index % config_.every != 0) return true;
  const std::size_t n = raw.ranges_m.size();
  const bool has_intensity = !raw.intensities.empty();
  const CloudCounts counts = toCloud(raw, *scratch_.cloud);
  summary_.no_return += counts.no_return;
  summary_.outside_limits += counts.outside_limits;
  summary_.returns += counts.returns;
  scratch_.name = scanFileName(summary_.written);
  if (start_next_) {
    // the first scan begins a stop anyway
    if (summary_.written > 0) stop_starts_.push_back(scratch_.name);
    start_next_ = false;
  }
  scratch_.viewpoint = raw.pose;
  scratch_.has_intensity = has_intensity;
  writeScan(dir_.path() / scratch_.name, scratch_, config_.encoding);

  summary_.min_beams = summary_.written == 0 ? n : std::min(summary_.min_beams, n);
  summary_.max_beams = std::max(summary_.max_beams, n);
  summary_.points += n;
  if (has_intensity) ++summary_.with_intensity;
  if (raw.wheel_angles_rad)
    wheels_.push_back({scratch_.name, raw.wheel_angles_rad->first, raw.wheel_angles_rad->second});
  summary_.range_min_m = std::min(summary_.range_min_m, raw.range_min_m);
  summary_.range_max_m = std::max(summary_.range_max_m, raw.range_max_m);
  ++summary_.written;
  return config_.max_scans == 0 || summary_.written < config_.max_scans;
}

SequenceWriteSummary SequenceWriter::commit(const std::string& sensor_name) {
  if (summary_.written == 0)
    throw InputError(summary_.out.string(), "",
                     "the input holds no scan to import: nothing was written",
                     "check the input file and the options (--from, --topic)");
  SequenceMeta meta;
  if (!sensor_name.empty()) meta.sensor_name = sensor_name;
  if (std::isfinite(summary_.range_min_m) && summary_.range_min_m >= 0.0)
    meta.range_min_m = summary_.range_min_m;
  if (std::isfinite(summary_.range_max_m) && summary_.range_max_m > summary_.range_min_m)
    meta.range_max_m = summary_.range_max_m;
  if (summary_.min_beams == summary_.max_beams && summary_.max_beams > 0)
    meta.beams = static_cast<int>(summary_.max_beams);
  meta.stop_starts = stop_starts_;
  writeSequenceMeta(dir_.path() / "sequence.json", meta);
  summary_.with_wheels = wheels_.size();
  if (!wheels_.empty()) writeWheelAnglesCsv(dir_.path() / "wheel_angles.csv", wheels_);
  dir_.commit();
  return summary_;
}

}  // namespace lidarcal::io
