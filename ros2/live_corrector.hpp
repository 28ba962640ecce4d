// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What the ROS 2 node does with each received LaserScan, apart from the transport: check it,
// correct its ranges in place with the rule of `lidarcal correct` (pipeline::correctLaserRanges
// through a pipeline::MemoCorrector, so node and corrected bags agree bit for bit) and say
// whether to publish it, drop it or stop.
//
// - The first well-formed scan decides whether the model belongs to the sensor (beam count,
//   range limits, as pipeline::checkModelFitsSensor): a model of another sensor is refused.
// - A malformed scan is dropped and counted, never published: no beams, a header field that is
//   not finite (angles, range limits), range_min above range_max, intensities neither empty nor
//   one per beam, or a beam count other than the sensor's (decided by the first scan). Ranges
//   that are NaN or inf are not malformed (REP 117: no return) and pass unchanged, as in `correct`.

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "calibration/filtering.hpp"
#include "common/calibration_model.hpp"
#include "pipeline/stages/bag_correct.hpp"
#include "pipeline/stages/stages.hpp"

namespace lidarcal::ros2 {

/// The fields of one received LaserScan the checks read; `ranges` is corrected in place.
struct ScanFields {
  float angle_min = 0, angle_max = 0, angle_increment = 0;  ///< rad
  float range_min = 0, range_max = 0;                       ///< m
  float* ranges = nullptr;      ///< m, `beams` values, corrected in place
  std::size_t beams = 0;        ///< number of ranges
  std::size_t intensities = 0;  ///< number of intensities
  /// the intensities themselves (`intensities` values; read only, for the watcher's copy of the
  /// raw scan); null: not given
  const float* intensity_values = nullptr;
};

/// Why a scan was dropped.
enum class DropReason { empty, non_finite_field, range_limits, intensities, beam_count, count_ };
const char* toString(DropReason r);

enum class ScanVerdict {
  publish,  ///< corrected: publish it
  drop,     ///< malformed: dropped (reason in dropReason(), text in message())
  refuse,   ///< the model is not this sensor's: stop (message() says why; exit status 2)
};

/// How the node corrects, from its parameters and the model file.
struct LiveSettings {
  std::string model_file;  ///< for messages
  std::string topic;       ///< the input topic, for messages
  calibration::InversionMethod method = calibration::InversionMethod::ls;  ///< inversion
  /// readings outside the fitted range
  calibration::Outside outside = calibration::kDefaultOutside;
  std::optional<std::string> sensor_name;  ///< checked against the model at the first scan when set
  bool force = false;  ///< apply a model whose range limits differ (with a warning)
};

/// Counts over the node's life.
struct LiveStats {
  /// scans corrected and published, and what happened to their returns
  pipeline::CorrectionStats correction;
  /// scans published uncorrected: learn mode before a model is learnt
  std::size_t uncorrected = 0;
  /// scans dropped, by reason
  std::array<std::size_t, static_cast<std::size_t>(DropReason::count_)> dropped{};
  std::size_t droppedTotal() const;
};

class LiveCorrector {
 public:
  /// `correct`: pipeline::modelCorrector(model, settings.method, settings.outside, model_file).
  LiveCorrector(const CalibrationModel& model, const LiveSettings& settings,
                const calibration::ReadingCorrector& correct);
  /// Without a model yet (learn mode): scans are checked and published uncorrected until
  /// useModel().
  explicit LiveCorrector(const LiveSettings& settings);

  /// Corrects from the next scan on with `model` (a model learnt from this sensor's scans, so the
  /// first scan's checks of the sensor are not made again); counts and the sensor's beam count
  /// carry on. `correct` as for the constructor.
  void useModel(const CalibrationModel& model, const calibration::ReadingCorrector& correct);
  bool hasModel() const { return correct_.has_value(); }  ///< false: scans pass uncorrected

  /// Checks and corrects one scan (see the header comment).
  ScanVerdict process(ScanFields& scan);
  /// Why the last scan was dropped or refused (empty after a published scan).
  const std::string& message() const { return message_; }
  DropReason dropReason() const { return reason_; }
  /// A warning from the sensor check at the first scan (range limits applied under force); empty
  /// otherwise.
  const std::string& sensorWarning() const { return sensor_warning_; }
  const LiveStats& stats() const { return stats_; }

 private:
  ScanVerdict drop(DropReason reason, std::string why);

  ScanVerdict checkSensor(std::size_t beams, double range_min, double range_max);

  CalibrationModel model_;
  LiveSettings settings_;
  // remembers the readings seen: a lookup per beam after the first scans; none: no model yet
  std::optional<pipeline::MemoCorrector> correct_;
  std::vector<float> ranges_;     // the scan's ranges, as correctLaserRanges takes them (reused)
  std::size_t sensor_beams_ = 0;  // the beam count of the first accepted scan (0: none yet)
  LiveStats stats_;
  std::string message_, sensor_warning_;
  DropReason reason_ = DropReason::empty;
};

}  // namespace lidarcal::ros2
