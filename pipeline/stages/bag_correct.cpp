// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/bag_correct.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "io/import_rosbag.hpp"
#include "io/rosbag_rewrite.hpp"

namespace lidarcal::pipeline {

calibration::CorrectedReading MemoCorrector::operator()(float reading_m) {
  std::uint32_t key = 0;
  std::memcpy(&key, &reading_m, sizeof key);
  if (const auto it = memo_.find(key); it != memo_.end()) return it->second;
  const calibration::CorrectedReading c = correct_(static_cast<double>(reading_m));
  if (memo_.size() < capacity_) memo_.emplace(key, c);
  return c;
}

void correctLaserRanges(std::vector<float>& ranges_m, double range_min_m, double range_max_m,
                        MemoCorrector& correct, CorrectionStats& stats) {
  stats.points += ranges_m.size();
  for (float& r : ranges_m) {
    // The importer's rule for a return (io/sequence_writer.cpp): anything else is not a reading.
    if (!std::isfinite(r) || !(r > 0.0f) || r < range_min_m || r > range_max_m) continue;
    const calibration::CorrectedReading c = correct(r);
    stats.add(c, r, r < correct.window().reading_min_m);
    // the reading itself when kept; NaN when dropped or unresolved
    r = static_cast<float>(c.range_m);
  }
}

SensorFacts firstScanFacts(const std::filesystem::path& bag, const std::string& topic,
                           BagScanReader read) {
  SensorFacts facts;
  io::RosbagConfig config;
  config.topic = topic;
  const io::ImportReport report = read(bag, config, [&](const io::RawScan& scan) {
    facts.range_min_m = scan.range_min_m;
    facts.range_max_m = scan.range_max_m;
    return false;  // the first message is enough
  });
  facts.sensor_name = report.sensor_name;
  facts.source = bag.string();
  facts.noun = "bag";
  return facts;
}

CorrectionStats correctBagRanges(const std::filesystem::path& in, const std::filesystem::path& out,
                                 const BagCorrection& c, BagRangesRewriter rewrite) {
  CorrectionStats stats;
  MemoCorrector memo(c.correct);
  const io::BagRewriteReport report =
      rewrite(in, out, c.topic, [&](std::vector<float>& ranges, const io::RawScan& scan) {
        checkModelBeams(c.model, ranges.size(),
                        in.string() + " (LaserScan " + std::to_string(scan.source_index) + ")",
                        c.model_file);
        correctLaserRanges(ranges, scan.range_min_m, scan.range_max_m, memo, stats);
      });
  stats.scans = report.scans;
  return stats;
}

SensorFacts bagSensorFacts(const std::filesystem::path& bag, const std::string& topic) {
  return firstScanFacts(bag, topic, io::readRosbag);
}

CorrectionStats correctRosbag(const std::filesystem::path& in, const std::filesystem::path& out,
                              const std::string& topic, const CalibrationModel& model,
                              const calibration::ReadingCorrector& correct,
                              const std::filesystem::path& model_file) {
  return correctBagRanges(in, out, BagCorrection{topic, model, correct, model_file},
                          io::rewriteRosbag);
}

}  // namespace lidarcal::pipeline
