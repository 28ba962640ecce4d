// SPDX-License-Identifier: BSD-3-Clause
#include "ros/node_watch.hpp"

#include <cstdint>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <std_msgs/String.h>

#include "io/atomic_file.hpp"
#include "io/model_io.hpp"
#include "pipeline/reports/watch_report.hpp"

namespace lidarcal::ros1 {
namespace {

/// Seconds between two warnings of one kind (bad pose messages, scans left out of watching).
constexpr double kWarnEveryS = 10.0;

/// A received pose (an Odometry's, or one transform of a TFMessage) as ros2::LivePoses takes it.
template <class Position>
ros2::ReceivedTransform receivedTransform(const std_msgs::Header& header, const std::string& child,
                                          const Position& p, const geometry_msgs::Quaternion& q) {
  ros2::ReceivedTransform t;
  t.stamp.sec = static_cast<std::int32_t>(header.stamp.sec);
  t.stamp.nanosec = header.stamp.nsec;
  t.parent = header.frame_id;
  t.child = child;
  t.x = p.x;
  t.y = p.y;
  t.z = p.z;
  t.qx = q.x;
  t.qy = q.y;
  t.qz = q.z;
  t.qw = q.w;
  return t;
}

/// "at 1 m +0.4 +- 0.3 mm, at 2 m ..., at 3 m ..." (the model's bias with its standard error).
std::string biasSummary(const CalibrationModel* m) {
  if (!m) return "none";
  std::string text;
  for (int d = 1; d <= 3; ++d)
    text += std::string(d > 1 ? ", " : "") + "at " + std::to_string(d) + " m " +
            watch::biasText(*m, static_cast<double>(d));
  return text;
}

std::uint8_t diagnosticLevel(watch::Health h) {
  switch (h) {
    case watch::Health::ok:
      return diagnostic_msgs::DiagnosticStatus::OK;
    case watch::Health::warn:
      return diagnostic_msgs::DiagnosticStatus::WARN;
    case watch::Health::error:
      return diagnostic_msgs::DiagnosticStatus::ERROR;
  }
  return diagnostic_msgs::DiagnosticStatus::STALE;
}

}  // namespace

PoseInput::PoseInput(ros::NodeHandle& nh, const ros2::PoseSource& source, ros2::LivePoses& poses)
    : poses_(poses) {
  const ros::TransportHints hints = ros::TransportHints().tcpNoDelay();
  if (source.kind == ros2::PoseSource::Kind::odom)
    subscribers_.push_back(nh.subscribe(source.name, 100, &PoseInput::onOdometry, this, hints));
  else
    subscribers_.push_back(nh.subscribe<tf2_msgs::TFMessage>(
        "/tf", 100, [this](const tf2_msgs::TFMessage::ConstPtr& m) { onTransforms(m, false); },
        ros::VoidConstPtr(), hints));
  // The sensor's mount (odom) or the static links of the chain (tf).
  subscribers_.push_back(nh.subscribe<tf2_msgs::TFMessage>(
      "/tf_static", 100, [this](const tf2_msgs::TFMessage::ConstPtr& m) { onTransforms(m, true); },
      ros::VoidConstPtr(), hints));
}

void PoseInput::onOdometry(const nav_msgs::Odometry::ConstPtr& msg) {
  const auto& pose = msg->pose.pose;
  if (const auto r = poses_.addOdometry(
          receivedTransform(msg->header, msg->child_frame_id, pose.position, pose.orientation)))
    ROS_WARN_THROTTLE(kWarnEveryS, "lidarcal_node: odometry message dropped: %s (%zu so far)",
                      ros2::toString(*r), poses_.stats().droppedTotal());
}

void PoseInput::onTransforms(const tf2_msgs::TFMessage::ConstPtr& msg, bool is_static) {
  for (const auto& t : msg->transforms)
    if (const auto r =
            poses_.addTransform(receivedTransform(t.header, t.child_frame_id,
                                                  t.transform.translation, t.transform.rotation),
                                is_static))
      ROS_WARN_THROTTLE(kWarnEveryS, "lidarcal_node: transform %s -> %s dropped: %s (%zu so far)",
                        t.header.frame_id.c_str(), t.child_frame_id.c_str(), ros2::toString(*r),
                        poses_.stats().droppedTotal());
}

WatchReporter::WatchReporter(ros::NodeHandle& nh, const WatchParameters& p) : params_(p) {
  if (p.mode != NodeMode::learn) return;
  candidate_topic_ = ros::names::resolve(p.candidate_topic);  // "~name": under the node's name
  candidates_ = nh.advertise<std_msgs::String>(candidate_topic_, 1, /*latch=*/true);
}

void WatchReporter::report(const ScanOutcome& out, const ScanPathStats& stats) {
  if (!out.not_watched.empty())
    ROS_WARN_THROTTLE(kWarnEveryS,
                      "lidarcal_node: a scan was not watched: %s (so far %zu scans without a "
                      "pose, %zu malformed)",
                      out.not_watched.c_str(), stats.without_pose, stats.malformed);
  for (const watch::CheckEvent& c : out.checks)
    if (c.alarm) ROS_WARN("lidarcal_node: %s", pipeline::checkLine(c).c_str());
  for (const watch::RefitEvent& r : out.refits) reportRefit(r);
  if (out.switched_to && !out.switch_error.empty())
    ROS_ERROR(
        "lidarcal_node: the watcher switched to model %llu, which cannot correct (%s); the "
        "scans are still corrected with the previous model",
        static_cast<unsigned long long>(*out.switched_to), out.switch_error.c_str());
}

void WatchReporter::reportRefit(const watch::RefitEvent& e) {
  const CalibrationModel* c = e.candidate.get();
  if (!c || !c->status.ok()) {
    ROS_INFO("lidarcal_node: the refit on scans %zu-%zu made no model: %s", e.stretch.first_scan,
             e.stretch.last_scan, c ? c->status.message.c_str() : "no candidate");
    return;
  }
  const std::string where = publishCandidate(*c);
  if (e.decision.adopt) {
    ROS_INFO("lidarcal_node: %s. Bias of the model before: %s; of model %llu now: %s. Candidate %s",
             pipeline::refitLine(e).c_str(), biasSummary(e.previous.get()).c_str(),
             static_cast<unsigned long long>(e.model_version), biasSummary(c).c_str(),
             where.c_str());
  } else {
    ROS_INFO(
        "lidarcal_node: candidate model from scans %zu-%zu (%.1f m) not adopted: %s. Its "
        "bias: %s; the model in use: %s. Candidate %s",
        e.stretch.first_scan, e.stretch.last_scan, e.stretch.length_m, e.decision.reason.c_str(),
        biasSummary(c).c_str(), biasSummary(e.previous.get()).c_str(), where.c_str());
  }
}

std::string WatchReporter::publishCandidate(const CalibrationModel& candidate) {
  const std::string text = io::modelJson(candidate).dump(2) + "\n";  // as model.json
  std_msgs::String msg;
  msg.data = text;
  candidates_.publish(msg);
  std::string where = "published on " + candidate_topic_;
  if (params_.candidate_file.empty()) return where;
  try {
    io::writeTextAtomically(params_.candidate_file, text);
    where += " and written to " + params_.candidate_file;
  } catch (const std::exception& e) {
    ROS_ERROR("lidarcal_node: the candidate model could not be written to %s: %s",
              params_.candidate_file.c_str(), e.what());
  }
  return where;
}

DiagnosticsOutput::DiagnosticsOutput(ros::NodeHandle& nh, double period_s, std::string name,
                                     std::string hardware_id, const ScanPath& path)
    : name_(std::move(name)), hardware_id_(std::move(hardware_id)), path_(path) {
  publisher_ = nh.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10);
  timer_ = nh.createTimer(ros::Duration(period_s), &DiagnosticsOutput::publish, this);
}

void DiagnosticsOutput::publish(const ros::TimerEvent&) {
  const watch::DiagnosticReport r = path_.report();
  diagnostic_msgs::DiagnosticStatus status;
  status.level = diagnosticLevel(r.level);
  status.name = name_;
  status.message = r.message;
  status.hardware_id = hardware_id_;
  for (const auto& [key, value] : r.values) {
    diagnostic_msgs::KeyValue kv;
    kv.key = key;
    kv.value = value;
    status.values.push_back(std::move(kv));
  }
  diagnostic_msgs::DiagnosticArray array;
  array.header.stamp = ros::Time::now();
  array.status.push_back(std::move(status));
  publisher_.publish(array);
}

}  // namespace lidarcal::ros1
