// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The field watcher: one engine behind `lidarcal watch` (a recording replayed) and the live
// nodes (watch and learn modes). Scan by scan it
//   1. follows the poles (pole_tracker.hpp) and keeps their sightings in a bounded window
//      (sighting_window.hpp);
//   2. every CheckSettings::every_m of travel, checks the model in use on the stretch since the
//      last completed check (model_check.hpp): the first checks form the model's baseline, which
//      is tested against zero, and every later check is tested against the record of checks
//      that passed (shift_history.hpp), at the false-alarm rate set (false_alarms.hpp): OK, or
//      an alarm (ERROR);
//   3. in learn mode, after an alarm (or from the start without a model), refits on the raw
//      readings after the stretch that raised it and switches when the candidate differs, is
//      determined and is plausible (model_switch.hpp).
// The engine never corrects a scan: the caller corrects with model() (a shared, immutable model
// that changes only at a switch), so correction never waits for a fit. Fits run either at the
// scan that asks for them (replay: the timeline is the same on every run) or on a thread of their
// own (live). Memory is bounded by the window, whatever the length of the drive.

#include <cstddef>
#include <future>
#include <memory>
#include <optional>

#include <Eigen/Core>

#include "common/calibration_model.hpp"
#include "io/import.hpp"
#include "watch/events.hpp"
#include "watch/false_alarms.hpp"
#include "watch/pole_tracker.hpp"
#include "watch/shift_history.hpp"
#include "watch/sighting_window.hpp"
#include "watch/watch_settings.hpp"

namespace lidarcal::watch {

/// Where the engine's fits run.
enum class FitExecution {
  at_scan,  ///< at the scan that asks for them, before observe() returns (replays, tests)
  /// on a thread of their own; results are taken in at a later observe(), and an observe() at
  /// which the next fit is due waits for the last (the stretches are those at_scan makes)
  background,
};

class Engine {
 public:
  /// `model`: the model in use, with status ok and alpha_covariance; null only in learn mode
  /// (nothing is corrected until a model is learnt). Throws std::invalid_argument for invalid
  /// settings or a model that cannot be checked (the caller words it for its user).
  Engine(const WatchSettings& settings, std::shared_ptr<const CalibrationModel> model,
         FitExecution execution, WatchSink sink = {});
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  /// Takes the next scan: its readings as the sensor gave them, its pose in the world frame
  /// (RawScan::pose) and stamp.
  void observe(const io::RawScan& scan);
  /// Waits for a fit under way and takes its result in (the end of a replay).
  void finish();

  /// The model to correct with now; null while none (learn mode without a model given).
  std::shared_ptr<const CalibrationModel> model() const { return model_; }
  /// The state now.
  const WatchState& state() const { return state_; }

 private:
  /// What one fit computes: a check of the model in use, a refit, or both.
  struct Fit {
    std::optional<ModelCheck> check;                    ///< the check, when one was asked for
    Stretch check_stretch;                              ///< its stretch
    std::uint64_t version = 0;                          ///< the model it checked
    std::shared_ptr<const CalibrationModel> candidate;  ///< the refit, when one was asked for
    Stretch refit_stretch;                              ///< its stretch
  };
  void advance(const io::RawScan& scan);
  void schedule(std::size_t index);
  void take(Fit fit);
  void poll(bool wait);
  void applyCheck(const Fit& fit);
  void applyRefit(const Fit& fit);
  SwitchTest switchTest() const;
  void updateLevel();
  bool testedAgainstZero() const;
  void decide(CheckEvent& e);
  void useModel(std::shared_ptr<const CalibrationModel> model);
  Stretch stretchOf(std::size_t first, std::size_t last) const;

  WatchSettings settings_;
  FitExecution execution_;
  WatchSink sink_;
  PoleTracker tracker_;
  SightingWindow window_;
  FalseAlarmBudget budget_;
  std::shared_ptr<const CalibrationModel> model_;
  WatchState state_;
  std::optional<io::RawScan> previous_;  // pose and stamp of the last scan (ranges cleared)
  double driving_h_ = 0.0;
  std::size_t stretch_first_ = 0;             // first scan of the next check's stretch
  double next_fit_m_ = 0.0;                   // travel at which the next fit is due
  double decided_m_ = 0.0, decided_h_ = 0.0;  // travel and driving at the last decision
  std::optional<std::size_t> learn_first_;    // learning: first scan of the refit's stretch
  std::size_t learn_refits_ = 0;              // refits judged since learning began
  std::future<Fit> running_;                  // a fit under way (background)
  bool alarmed_ = false;  // a test rejected the model in use (latched until it is replaced)
  CheckEvent alarm_;      // that first rejection, the alarm
  Eigen::Vector2d alarm_mean_ = Eigen::Vector2d::Zero();  // the record's mean shift then
  bool rejected_ = false;  // the model's baseline failed its absolute test: wrong from the start
  ShiftHistory record_;    // the checks that passed under the model in use
  ShiftHistory baseline_;  // its baseline's checks with the fit's own bias out
  ShiftHistory alarm_record_;            // the record when the alarm came
  ShiftHistory after_alarm_;             // the checks since: a switch needs them to differ from it
  std::array<double, 2> distances_m_{};  // the model's reference distances
  Eigen::Matrix2d model_covariance_ = Eigen::Matrix2d::Zero();  // its own error there
};

}  // namespace lidarcal::watch
