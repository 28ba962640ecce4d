// SPDX-License-Identifier: BSD-3-Clause
#include "ros2/live_corrector.hpp"

#include <algorithm>
#include <cmath>

#include "io/import.hpp"

namespace lidarcal::ros2 {

const char* toString(DropReason r) {
  switch (r) {
    case DropReason::empty:
      return "no beams";
    case DropReason::non_finite_field:
      return "a header field not finite";
    case DropReason::range_limits:
      return "range_min above range_max";
    case DropReason::intensities:
      return "intensities not one per beam";
    case DropReason::beam_count:
      return "another beam count";
    case DropReason::count_:
      break;
  }
  return "?";
}

std::size_t LiveStats::droppedTotal() const {
  std::size_t n = 0;
  for (std::size_t d : dropped) n += d;
  return n;
}

LiveCorrector::LiveCorrector(const CalibrationModel& model, const LiveSettings& settings,
                             const calibration::ReadingCorrector& correct)
    : model_(model), settings_(settings), correct_(std::in_place, correct) {}

LiveCorrector::LiveCorrector(const LiveSettings& settings) : settings_(settings) {}

void LiveCorrector::useModel(const CalibrationModel& model,
                             const calibration::ReadingCorrector& correct) {
  model_ = model;
  correct_.emplace(correct);
}

ScanVerdict LiveCorrector::drop(DropReason reason, std::string why) {
  reason_ = reason;
  message_ = std::move(why);
  ++stats_.dropped[static_cast<std::size_t>(reason)];
  return ScanVerdict::drop;
}

/// The first accepted scan: is the model this sensor's (beams, range limits)? Without a model
/// there is nothing to check; the scan's beam count is kept either way.
ScanVerdict LiveCorrector::checkSensor(std::size_t beams, double range_min, double range_max) {
  if (correct_) {
    try {
      pipeline::checkModelBeams(model_, beams, "topic " + settings_.topic, settings_.model_file);
      const pipeline::SensorFacts facts{settings_.sensor_name, range_min, range_max,
                                        "topic " + settings_.topic, "topic"};
      sensor_warning_ = pipeline::checkModelFitsSensor(model_, facts, settings_.model_file,
                                                       settings_.force, settings_.outside);
    } catch (const std::exception& e) {
      message_ = e.what();
      return ScanVerdict::refuse;
    }
  }
  sensor_beams_ = beams;
  return ScanVerdict::publish;
}

ScanVerdict LiveCorrector::process(ScanFields& scan) {
  message_.clear();
  if (scan.beams == 0) return drop(DropReason::empty, "a scan without beams");
  for (float v :
       {scan.angle_min, scan.angle_max, scan.angle_increment, scan.range_min, scan.range_max})
    if (!std::isfinite(v))
      return drop(DropReason::non_finite_field,
                  "a scan whose angles or range limits are not all finite");
  if (scan.range_min > scan.range_max)
    return drop(DropReason::range_limits,
                "a scan whose range_min " + std::to_string(scan.range_min) +
                    " m is above its range_max " + std::to_string(scan.range_max) + " m");
  if (scan.intensities != 0 && scan.intensities != scan.beams)
    return drop(DropReason::intensities, "a scan of " + std::to_string(scan.beams) +
                                             " ranges and " + std::to_string(scan.intensities) +
                                             " intensities");
  if (sensor_beams_ != 0 && scan.beams != sensor_beams_)
    return drop(DropReason::beam_count, "a scan of " + std::to_string(scan.beams) +
                                            " beams from a sensor of " +
                                            std::to_string(sensor_beams_));
  // As `correct IN.bag`: the limits as the decimals they were written as.
  const double range_min = io::float32Decimal(scan.range_min),
               range_max = io::float32Decimal(scan.range_max);
  if (sensor_beams_ == 0 && checkSensor(scan.beams, range_min, range_max) == ScanVerdict::refuse)
    return ScanVerdict::refuse;
  if (!correct_) {
    ++stats_.uncorrected;
    return ScanVerdict::publish;
  }
  ranges_.assign(scan.ranges, scan.ranges + scan.beams);
  pipeline::correctLaserRanges(ranges_, range_min, range_max, *correct_, stats_.correction);
  std::copy(ranges_.begin(), ranges_.end(), scan.ranges);
  ++stats_.correction.scans;
  return ScanVerdict::publish;
}

}  // namespace lidarcal::ros2
