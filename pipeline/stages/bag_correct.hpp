// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// `lidarcal correct IN.bag --model model.json --out OUT.bag`: the bag copied with the ranges of
// one LaserScan topic corrected reading by reading (calibration::correctReading, as `correct`
// does for a sequence). Readings the importer would not turn into points (NaN, inf, <= 0,
// outside the message's range_min..range_max) are left as they are; a reading dropped or
// without a distance becomes NaN (REP 117: an invalid measurement).

#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "calibration/filtering.hpp"
#include "common/calibration_model.hpp"
#include "io/bag_scans.hpp"
#include "io/import.hpp"
#include "io/rosbag_rewrite.hpp"
#include "pipeline/stages/stages.hpp"

namespace lidarcal::pipeline {

/// A ReadingCorrector that remembers the readings it has corrected, keyed by their float value:
/// sensors report quantised readings (1 mm, 0.25 mm), so after the first scans almost every
/// reading is a lookup instead of a polynomial root search (the node's latency budget). Results
/// are those of the corrector, bit for bit. At most `capacity` readings are remembered (default
/// 2^20, about 40 MB); beyond, readings are corrected without being stored.
class MemoCorrector {
 public:
  explicit MemoCorrector(calibration::ReadingCorrector correct,
                         std::size_t capacity = std::size_t{1} << 20)
      : correct_(std::move(correct)), capacity_(capacity) {}
  calibration::CorrectedReading operator()(float reading_m);
  std::size_t remembered() const { return memo_.size(); }
  /// The readings the fit itself corrects.
  const calibration::CorrectionWindow& window() const { return correct_.window; }

 private:
  calibration::ReadingCorrector correct_;
  std::size_t capacity_;
  std::unordered_map<std::uint32_t, calibration::CorrectedReading> memo_;  // float bits -> result
};

/// Corrects the ranges of one LaserScan in place; the same rule for bags and the ROS node.
/// `stats` counts the returns (scans is not touched).
void correctLaserRanges(std::vector<float>& ranges_m, double range_min_m, double range_max_m,
                        MemoCorrector& correct, CorrectionStats& stats);

/// A reader of a bag's scans (io::readRosbag, io::readRosbag2) and a rewriter of its LaserScan
/// ranges (io::rewriteRosbag, io::rewriteRosbag2): ROS 1 and ROS 2 bags are corrected alike.
using BagScanReader = io::ImportReport (*)(const std::filesystem::path&, const io::RosbagConfig&,
                                           const io::ScanCallback&);
using BagRangesRewriter = io::BagRewriteReport (*)(const std::filesystem::path&,
                                                   const std::filesystem::path&, const std::string&,
                                                   const io::RangesCallback&);

/// What the first LaserScan of the bag's topic, read by `read`, says about the sensor.
SensorFacts firstScanFacts(const std::filesystem::path& bag, const std::string& topic,
                           BagScanReader read);

/// The model applied to a bag's topic.
struct BagCorrection {
  const std::string& topic;
  const CalibrationModel& model;
  const calibration::ReadingCorrector& correct;
  const std::filesystem::path& model_file;  ///< named in errors
};

/// Writes `out` from `in` with `rewrite`, the topic's ranges corrected; refuses a message whose
/// beam count differs from the model's (InputError naming the message).
CorrectionStats correctBagRanges(const std::filesystem::path& in, const std::filesystem::path& out,
                                 const BagCorrection& c, BagRangesRewriter rewrite);

/// What the first LaserScan of the bag's topic says about the sensor (as `import` would write
/// it to sequence.json), for checkModelFitsSensor.
SensorFacts bagSensorFacts(const std::filesystem::path& bag, const std::string& topic);

/// Writes `out` (a new file; the caller makes it atomic) from `in`; refuses a message whose beam
/// count differs from the model's (InputError naming the message).
CorrectionStats correctRosbag(const std::filesystem::path& in, const std::filesystem::path& out,
                              const std::string& topic, const CalibrationModel& model,
                              const calibration::ReadingCorrector& correct,
                              const std::filesystem::path& model_file);

}  // namespace lidarcal::pipeline
