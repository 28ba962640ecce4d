// SPDX-License-Identifier: BSD-3-Clause
#include "ros/scan_path.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <thread>
#include <utility>

#include "pipeline/stages/stages.hpp"

namespace lidarcal::ros1 {
namespace {

pipeline::MemoCorrector correctorOf(const CalibrationModel& model, const ScanPathSettings& s,
                                    const std::string& model_file) {
  return pipeline::MemoCorrector(pipeline::modelCorrector(model, s.method, s.outside, model_file));
}

/// A scan the watcher can take: beams, finite angles, a range window (range_max may be inf).
bool watchable(const io::LaserScanView& m) {
  return m.count > 0 && std::isfinite(m.angle_min) && std::isfinite(m.angle_increment) &&
         std::isfinite(m.range_min) && !std::isnan(m.range_max) && m.range_min < m.range_max;
}

/// The watcher, its threads (the worker and the fits it starts) at a lower priority than the
/// caller's: on Linux each thread has a nice value of its own and the threads it starts inherit
/// it, so the watcher is started from a short-lived thread that lowered its own. On a busy CPU
/// the correction of the next scan then comes before detection and fits.
std::unique_ptr<watch::LiveWatcher> startWatcher(const ScanPathSettings& s,
                                                 std::shared_ptr<const CalibrationModel> model) {
  std::unique_ptr<watch::LiveWatcher> watcher;
  std::exception_ptr error;
  std::thread starter([&] {
    const id_t self = static_cast<id_t>(gettid());
    errno = 0;
    const int nice = getpriority(PRIO_PROCESS, self);
    // Best effort: if the nice value cannot be raised, the watcher runs at the caller's.
    if (errno == 0) (void)setpriority(PRIO_PROCESS, self, std::min(19, nice + s.watcher_nice));
    try {
      watcher = std::make_unique<watch::LiveWatcher>(*s.watch, std::move(model), s.queue_scans);
    } catch (...) {
      error = std::current_exception();
    }
  });
  starter.join();
  if (error) std::rethrow_exception(error);
  return watcher;
}

/// The counts of the correction, for /diagnostics.
void addCorrectionCounts(const ScanPathStats& s, watch::DiagnosticReport& r) {
  const pipeline::CorrectionStats& c = s.correction;
  auto add = [&r](const char* key, std::size_t n) {
    r.values.emplace_back(key, std::to_string(n));
  };
  add("scans received", c.scans);
  add("scans passed uncorrected (no model yet)", s.uncorrected_scans);
  add("returns corrected", c.corrected + c.extrapolated);
  add("of them beyond the fitted range", c.extrapolated);
  add("returns beyond the fitted range left uncorrected", c.outside);
  add("returns without a distance", c.unresolved);
}

}  // namespace

/// The corrector of the learnt model `version`, warmed up on the readings of a recent scan
/// (the next scans' resemble them).
ScanPath::PreparedModel ScanPath::prepareModel(std::shared_ptr<const CalibrationModel> model,
                                               std::uint64_t version,
                                               const ScanPathSettings& settings,
                                               const std::vector<float>& recent) {
  PreparedModel p;
  p.version = version;
  const std::string name = "the learnt model " + std::to_string(version);
  try {
    if (!model) throw std::invalid_argument("the watcher holds no model");
    pipeline::checkModelInvertible(*model, name, settings.outside);
    p.correct.emplace(correctorOf(*model, settings, name));
    for (float r : recent)
      if (std::isfinite(r) && r > 0.0f) (*p.correct)(r);
    p.model = std::move(model);
  } catch (const std::exception& e) {
    p.error = e.what();
  }
  return p;
}

ScanPath::ScanPath(const ScanPathSettings& settings, std::shared_ptr<const CalibrationModel> model)
    : settings_(settings), model_(std::move(model)) {
  if (!settings_.watch && !model_) throw std::invalid_argument("apply mode needs a model");
  if (model_) {
    correct_.emplace(correctorOf(*model_, settings_, settings_.model_file));
    version_ = 1;
  }
  if (!settings_.watch) return;
  watcher_ = startWatcher(settings_, model_);
  version_ = seen_version_ = watcher_->modelVersion();
  poses_.emplace(settings_.poses);
}

ScanPath::~ScanPath() {
  for (std::thread* t : {&builder_, &retirer_})
    if (t->joinable()) t->join();
}

ScanOutcome ScanPath::process(const io::LaserScanView& msg, const std::string& frame_id,
                              std::vector<float>& ranges) {
  ScanOutcome out;
  if (watcher_) {
    offer(msg, frame_id, out);  // the raw readings, before they are corrected
    out.checks = watcher_->takeChecks();
    out.refits = watcher_->takeRefits();
    followSwitch(msg, out);
  }
  ++stats_.correction.scans;
  if (!correct_) {
    ++stats_.uncorrected_scans;
    return out;
  }
  pipeline::correctLaserRanges(ranges, io::float32Decimal(msg.range_min),
                               io::float32Decimal(msg.range_max), *correct_, stats_.correction);
  out.corrected = true;
  return out;
}

void ScanPath::offer(const io::LaserScanView& msg, const std::string& frame_id, ScanOutcome& out) {
  if (!watchable(msg)) {
    ++stats_.malformed;
    out.not_watched = "a scan without beams, or whose angles or range limits are not finite";
    return;
  }
  ros2::RosTime stamp;
  stamp.sec = static_cast<std::int32_t>(msg.stamp_sec);
  stamp.nanosec = msg.stamp_nanosec;
  const ros2::PoseLookup pose = poses_->at(frame_id, stamp);
  if (!pose.pose) {
    ++stats_.without_pose;
    out.not_watched = "no pose of its frame at its stamp: " + pose.why;
    return;
  }
  io::RawScan raw;
  io::fillRawScan(msg, io::RosbagConfig{}, raw);  // copies the readings
  raw.pose = *pose.pose;
  raw.frame_id = frame_id;
  raw.source_index = stats_.correction.scans;
  out.watched = watcher_->offer(std::move(raw));
  if (!out.watched) out.not_watched = "the watcher is behind (its queue is full)";
}

// A switch, without a scan that waits for it: building a corrector takes longer than correcting
// a scan, and so does freeing one (it remembers every reading seen). The new model's corrector is
// built on a thread of its own while the scans are still corrected with the model before, and
// used from the first scan after it is ready; the one before is freed on another thread. (Plain
// threads joined at the next switch, not std::async: releasing its future waits for the thread.)
void ScanPath::followSwitch(const io::LaserScanView& msg, ScanOutcome& out) {
  if (preparing_.valid() &&
      preparing_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    PreparedModel p = preparing_.get();
    out.switched_to = p.version;
    out.switch_error = std::move(p.error);
    if (p.correct) {
      if (retirer_.joinable()) retirer_.join();  // the switch before's, ended long ago
      retirer_ = std::thread([before = std::move(correct_)]() mutable { before.reset(); });
      correct_ = std::move(p.correct);
      model_ = std::move(p.model);
      version_ = p.version;
    }
  }
  const std::uint64_t version = watcher_->modelVersion();
  if (version == seen_version_ || preparing_.valid()) return;
  // The model may be a newer one than `version` already: then the next scan builds again.
  seen_version_ = version;
  if (builder_.joinable()) builder_.join();  // the switch before's, ended long ago
  std::packaged_task<PreparedModel()> build(
      [model = watcher_->model(), version, settings = settings_,
       recent = std::vector<float>(msg.ranges, msg.ranges + msg.count)] {
        return prepareModel(model, version, settings, recent);
      });
  preparing_ = build.get_future();
  builder_ = std::thread(std::move(build));
}

watch::DiagnosticReport ScanPath::report() const {
  watch::DiagnosticReport r;
  if (watcher_) {
    const std::size_t not_watched = stats_.without_pose + stats_.malformed + watcher_->dropped();
    r = watch::diagnosticReport(watcher_->state(), watcher_->model().get(), *settings_.watch,
                                not_watched);
    r.values.emplace_back("scans without a pose", std::to_string(stats_.without_pose));
  } else {
    r.level = watch::Health::ok;
    r.message =
        "correcting with " + settings_.model_file + " (apply mode: the model is not checked)";
    r.values.emplace_back("mode", "apply");
    r.values.emplace_back("model", settings_.model_file);
    if (model_) watch::addBiasValues(*model_, r.values);
  }
  addCorrectionCounts(stats_, r);
  return r;
}

}  // namespace lidarcal::ros1
