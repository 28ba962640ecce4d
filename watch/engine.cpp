// SPDX-License-Identifier: BSD-3-Clause
#include "watch/engine.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/pose2.hpp"

namespace lidarcal::watch {

namespace {

/// Steps longer than this between two stamps are a pause in the recording, not driving time.
constexpr double kMaxDrivingStepS = 1.0;
/// A pose that moves less than this between scans is standing still (no driving time).
constexpr double kStillM = 1e-3, kStillRad = 1e-3;

WatchSettings validated(const WatchSettings& s) {
  s.validate();
  return s;
}

std::size_t windowCapacity(const WatchSettings& s) {
  return s.mode == Mode::learn ? std::max(s.check.max_scans, s.learn.max_scans) : s.check.max_scans;
}

void checkModelUsable(const CalibrationModel* m, Mode mode) {
  if (!m) {
    if (mode != Mode::learn) throw std::invalid_argument("watch mode needs a model to check");
    return;
  }
  if (!m->status.ok())
    throw std::invalid_argument("the model has no usable fit: " + m->status.message);
  const std::size_t n = m->model.bias.alpha.size();
  if (n == 0 || m->alpha_covariance.size() != n * n)
    throw std::invalid_argument(
        "the model records no alpha_covariance, so a check cannot tell its own error from a "
        "change of the sensor");
}

}  // namespace

const char* toString(Test t) {
  switch (t) {
    case Test::none:
      return "none";
    case Test::baseline:
      return "baseline";
    case Test::absolute:
      return "absolute";
    case Test::change:
      return "change";
  }
  return "?";
}

const char* toString(Health h) {
  switch (h) {
    case Health::ok:
      return "OK";
    case Health::warn:
      return "WARN";
    case Health::error:
      return "ERROR";
  }
  return "?";
}

Engine::Engine(const WatchSettings& settings, std::shared_ptr<const CalibrationModel> model,
               FitExecution execution, WatchSink sink)
    : settings_(validated(settings)),
      execution_(execution),
      sink_(std::move(sink)),
      tracker_(settings_.detection, settings_.association),
      window_(windowCapacity(settings_)),
      budget_(settings_.false_alarms),
      record_(settings_.check.record_checks),
      baseline_(settings_.check.baseline_checks) {
  checkModelUsable(model.get(), settings_.mode);
  if (model) useModel(std::move(model));
  state_.learning = !model_;
  next_fit_m_ = settings_.check.every_m;
  if (!model_) learn_first_ = 0;
  state_.message = model_ ? "no check yet" : "learning: no model in use, scans pass uncorrected";
}

Engine::~Engine() {
  if (running_.valid()) running_.wait();
}

void Engine::advance(const io::RawScan& scan) {
  double step_m = 0.0, step_h = 0.0;
  if (previous_) {
    const Pose2& a = previous_->pose;
    step_m = std::hypot(scan.pose.x_m - a.x_m, scan.pose.y_m - a.y_m);
    const bool moved =
        step_m > kStillM || std::abs(wrapAngle(scan.pose.yaw_rad - a.yaw_rad)) > kStillRad;
    const double dt = scan.stamp_s - previous_->stamp_s;
    if (moved && std::isfinite(dt) && dt > 0.0) step_h = std::min(dt, kMaxDrivingStepS) / 3600.0;
  } else {
    previous_.emplace();
  }
  previous_->pose = scan.pose;
  previous_->stamp_s = scan.stamp_s;
  state_.travel_m += step_m;
  driving_h_ += step_h;
  budget_.expose(step_m / 1000.0, step_h);
}

void Engine::observe(const io::RawScan& scan) {
  const std::size_t index = state_.scans++;
  advance(scan);
  TrackedScan tracked = tracker_.track(scan, index);
  window_.rename(tracked.merged);
  WatchedScan w;
  w.index = index;
  w.stamp_s = scan.stamp_s;
  w.pose = scan.pose;
  w.travel_m = state_.travel_m;
  w.driving_h = driving_h_;
  w.range_min_m = scan.range_min_m;
  w.range_max_m = scan.range_max_m;
  w.poles = std::move(tracked.poles);
  window_.push(std::move(w));
  state_.sightings = window_.sightings();
  state_.tracks = tracker_.tracksAlive();
  // A fit due while the last one still runs waits for it here (on the watcher's thread, never
  // the caller's correction): every stretch is then decided as at_scan decides it.
  poll(state_.travel_m >= next_fit_m_);
  if (!running_.valid()) schedule(index);
  updateLevel();
}

void Engine::finish() {
  poll(true);
  updateLevel();
}

Stretch Engine::stretchOf(std::size_t first, std::size_t last) const {
  Stretch s;
  const WatchedScan* a = window_.find(first);
  const WatchedScan* b = window_.find(last);
  s.first_scan = first;
  s.last_scan = last;
  if (a && b) {
    s.travel_m = b->travel_m;
    s.length_m = b->travel_m - a->travel_m;
    s.stamp_s = b->stamp_s;
  }
  return s;
}

void Engine::schedule(std::size_t index) {
  if (state_.travel_m < next_fit_m_) return;
  next_fit_m_ = state_.travel_m + settings_.check.every_m;
  const std::size_t oldest = window_.oldest().index;
  Fit fit;
  SpanRules rules{settings_.check.min_sightings, settings_.check.landmark_radius_m};
  LandmarkObservations check_obs, refit_obs;
  if (model_) {
    // The check's stretch: since the last decision, at most check.max_scans long.
    const std::size_t first = std::max(
        {stretch_first_, oldest, index + 1 - std::min(index + 1, settings_.check.max_scans)});
    fit.check_stretch = stretchOf(first, index);
    fit.version = state_.model_version;
    check_obs = window_.observations(first, index, rules);
    fit.check.emplace();
  }
  const bool refit = settings_.mode == Mode::learn && learn_first_;
  if (refit) {
    const std::size_t first = std::max(*learn_first_, oldest);
    fit.refit_stretch = stretchOf(first, index);
    refit_obs = window_.observations(first, index, rules);
  }
  if (!fit.check && !refit) return;
  const std::shared_ptr<const CalibrationModel> model = model_;
  const WatchSettings settings = settings_;
  const std::array<double, 2> distances = distances_m_;
  const int replicas = testedAgainstZero() ? settings_.check.bias_replicas : 0;
  auto work = [fit, model, settings, refit, distances, replicas, check_obs = std::move(check_obs),
               refit_obs = std::move(refit_obs)]() mutable {
    if (fit.check)
      fit.check = checkModel(check_obs, *model, distances,
                             CheckFit{settings.threads, replicas, fit.check_stretch.first_scan});
    if (refit)
      fit.candidate = std::make_shared<const CalibrationModel>(
          refitModel(refit_obs, settings.learn, settings.threads));
    return fit;
  };
  if (execution_ == FitExecution::at_scan)
    take(work());
  else
    running_ = std::async(std::launch::async, std::move(work));
}

void Engine::poll(bool wait) {
  if (!running_.valid()) return;
  if (!wait && running_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  take(running_.get());
}

void Engine::take(Fit fit) {
  if (fit.check) applyCheck(fit);
  if (fit.candidate) applyRefit(fit);
}

void Engine::useModel(std::shared_ptr<const CalibrationModel> model) {
  model_ = std::move(model);
  ++state_.model_version;
  distances_m_ = referenceDistances(*model_);
  model_covariance_ = modelShiftCovariance(*model_, distances_m_);
  record_.clear();
  baseline_.clear();
  alarm_record_.clear();
  after_alarm_.clear();
  rejected_ = alarmed_ = false;
  alarm_ = CheckEvent{};
  state_.last_check = CheckEvent{};
}

/// Whether the next check will be tested against zero, where the fit's own bias does not
/// cancel: a check of the baseline, or in learn mode one after the baseline failed (the switch
/// test then asks whether the checks since still say the model is wrong: switchTest()).
bool Engine::testedAgainstZero() const {
  return record_.size() < settings_.check.baseline_checks ||
         (settings_.mode == Mode::learn && rejected_);
}

/// Tests one check (shift_history.hpp) and spends the level the exposure allows. The change
/// tests compare fitted shifts, whose shared bias cancels; the tests against zero take the
/// shifts with the fit's own bias out.
void Engine::decide(CheckEvent& e) {
  const Shift shift = fittedShift(e.check);
  const std::size_t baseline = settings_.check.baseline_checks;
  e.record = record_.size();
  if (record_.size() + 1 < baseline) {
    record_.add(shift);
    baseline_.add(unbiasedShift(e.check));
    e.test = Test::baseline;
    return;
  }
  if (record_.size() + 1 == baseline) {
    record_.add(shift);
    baseline_.add(unbiasedShift(e.check));
    e.test = Test::absolute;
    e.f = baseline_.absolute(model_covariance_);
  } else {
    e.test = Test::change;
    e.f = record_.change(shift);
  }
  e.exposure = budget_.pending();
  e.level = budget_.spend();
  e.exceeds = e.f.p < e.level;
  // The first rejection under a model is the alarm; the state stays ERROR until the model is
  // replaced. Every check joins the record whatever its test said, so that each later test
  // keeps its size (the record does not depend on the decisions).
  e.alarm = e.exceeds && !alarmed_;
  if (e.alarm) {
    alarm_ = e;
    // the baseline's (its bias out), or the passed checks' before this one
    alarm_mean_ = e.test == Test::absolute ? baseline_.mean() : record_.mean();
    alarm_record_ = record_;
    after_alarm_.clear();
  } else if (alarmed_) {
    after_alarm_.add(rejected_ ? unbiasedShift(e.check) : shift);
  }
  if (e.test == Test::change) record_.add(shift);
  if (e.test == Test::absolute) {
    rejected_ = e.exceeds;
    state_.absolute_p = e.f.p;
    state_.absolute_level = e.level;
  }
  alarmed_ = alarmed_ || e.exceeds;
  ++state_.checks;
  state_.alarms += e.alarm ? 1 : 0;
}

void Engine::applyCheck(const Fit& fit) {
  CheckEvent e;
  e.stretch = fit.check_stretch;
  e.decided_at = state_.scans - 1;
  e.check = *fit.check;
  e.model_version = fit.version;
  // A check of a model no longer in use (a switch came first) decides nothing.
  if (e.check.status.ok() && fit.version == state_.model_version) {
    decide(e);
    stretch_first_ = fit.check_stretch.last_scan + 1;
    if (e.test != Test::baseline) {
      decided_m_ = state_.travel_m;
      decided_h_ = driving_h_;
    }
    state_.last_check = e;
    if (e.alarm && settings_.mode == Mode::learn && !learn_first_) {
      // Learn from the scans after the stretch that showed the change (the change came within
      // it or before: every later scan was read after it); a model wrong from the start, from
      // all the window holds.
      learn_first_ =
          e.test == Test::absolute ? window_.oldest().index : fit.check_stretch.last_scan + 1;
      learn_refits_ = 0;
      next_fit_m_ = state_.travel_m;  // the first refit at the next scan
    }
  }
  if (sink_.check) sink_.check(e);
}

void Engine::applyRefit(const Fit& fit) {
  RefitEvent e;
  e.stretch = fit.refit_stretch;
  e.decided_at = state_.scans - 1;
  e.candidate = fit.candidate;
  e.previous = model_;
  // One alarm is followed by refit after refit against the model in use: refit k is tested at
  // switch_level / (k (k + 1)), which sums to switch_level over all of them, so a false alarm
  // leads to a switch with probability at most switch_level.
  ++learn_refits_;
  LearnSettings learn = settings_.learn;
  const double k = static_cast<double>(learn_refits_);
  learn.switch_level /= k * (k + 1.0);
  e.decision = decideSwitch(*fit.candidate, model_.get(), switchTest(), learn);
  if (e.decision.adopt) {
    useModel(fit.candidate);
    ++state_.switches;
    learn_first_.reset();
    stretch_first_ = e.decided_at + 1;  // the new model is checked on what comes next
    budget_.spend();                    // and its first level counts from now
    decided_m_ = state_.travel_m;
    decided_h_ = driving_h_;
  } else if (e.previous &&
             e.stretch.last_scan + 1 - e.stretch.first_scan >= settings_.learn.max_scans) {
    // A full window since the alarm and still no candidate to switch to: stop learning; the
    // next alarm starts again.
    learn_first_.reset();
    e.decision.reason += "; learning stops until the next alarm";
  }
  e.model_version = state_.model_version;
  if (sink_.refit) sink_.refit(e);
}

/// Whether the sensor differs from the model in use since the alarm: the checks made since
/// against those before it, or against zero when the model was wrong from the start (its
/// baseline failed the absolute test). Those checks are fits of the kind the record holds, over
/// stretches after the alarm's, so under no change they are draws of the record's law.
SwitchTest Engine::switchTest() const {
  SwitchTest t;
  if (!model_) return t;
  const std::size_t need = rejected_ ? 2 : 1;
  if (after_alarm_.size() < need) {
    t.why_not = "checks since the alarm: " + std::to_string(after_alarm_.size()) + " of the " +
                std::to_string(need) + " needed";
    return t;
  }
  t.f = rejected_ ? after_alarm_.absolute(model_covariance_) : after_alarm_.sameMean(alarm_record_);
  t.checks = after_alarm_.size();
  t.tested = true;
  return t;
}

void Engine::updateLevel() {
  state_.learning = learn_first_.has_value();
  state_.since_check_m = state_.travel_m - decided_m_;
  state_.since_check_s = 3600.0 * (driving_h_ - decided_h_);
  state_.driving_h = driving_h_;
  const CheckEvent& c = state_.last_check;
  const bool stale =
      state_.since_check_m > settings_.check.stale_after_spans * settings_.check.every_m;
  const char* learning = state_.learning ? "; learning a new one" : "";
  char text[400];
  if (!model_) {
    state_.level = Health::warn;
    std::snprintf(text, sizeof text, "learning: no model in use yet, scans pass uncorrected");
  } else if (rejected_) {
    state_.level = Health::error;
    std::snprintf(text, sizeof text,
                  "the model does not describe this sensor: its corrected readings are off by "
                  "%+.1f mm at %.2f m and %+.1f mm at %.2f m over the first %zu checks "
                  "(p = %.2g, below the level %.2g)%s",
                  1000.0 * alarm_mean_(0), distances_m_[0], 1000.0 * alarm_mean_(1),
                  distances_m_[1], settings_.check.baseline_checks, state_.absolute_p,
                  state_.absolute_level, learning);
  } else if (alarmed_) {
    state_.level = Health::error;
    const ModelCheck& a = alarm_.check;
    std::snprintf(text, sizeof text,
                  "the sensor has changed: at scan %zu (%.1f m) its corrected readings moved to "
                  "%+.1f mm at %.2f m and %+.1f mm at %.2f m against the passed checks' %+.1f "
                  "and %+.1f mm (p = %.2g, below the level %.2g)%s",
                  alarm_.decided_at, alarm_.stretch.travel_m, 1000.0 * a.shift_m[0],
                  a.distance_m[0], 1000.0 * a.shift_m[1], a.distance_m[1], 1000.0 * alarm_mean_(0),
                  1000.0 * alarm_mean_(1), alarm_.f.p, alarm_.level, learning);
  } else if (c.test == Test::none) {
    state_.level = Health::warn;
    std::snprintf(text, sizeof text, "%s",
                  state_.switches ? "switched to a learnt model; not checked yet" : "no check yet");
  } else if (c.test == Test::baseline) {
    state_.level = Health::warn;
    std::snprintf(text, sizeof text, "baseline: %zu of %zu checks made, no test yet",
                  record_.size(), settings_.check.baseline_checks);
  } else if (stale) {
    state_.level = Health::warn;
    std::snprintf(text, sizeof text, "not checked over the last %.0f m: no poles the fit can use",
                  state_.since_check_m);
  } else {
    state_.level = Health::ok;
    std::snprintf(text, sizeof text, "the model holds (last test: p = %.2g, level %.2g)", c.f.p,
                  c.level);
  }
  state_.message = text;
}

}  // namespace lidarcal::watch
