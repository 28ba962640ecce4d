// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What the node publishes besides its scans, each a writer made through the node's
// RosParticipant (so the graph names the node as its publisher):
//
// - RosoutLogger: rcl_interfaces/msg/Log on /rosout, one message per log line, with the QoS rcl
//   gives it (rcl: rcl/include/rcl/logging_rosout.h): reliable, transient local, keep last 1000,
//   lifespan 10 s;
// - DiagnosticsPublisher: diagnostic_msgs/msg/DiagnosticArray on /diagnostics, ROS 2's default
//   profile (reliable, keep last 10, volatile);
// - TextPublisher: std_msgs/msg/String, e.g. a candidate model as JSON on ~/candidate_model,
//   transient local with keep last 1 by default so that a subscriber that asks for transient
//   local gets the last one when it joins.
//
// Publishing never throws: a failed write is counted (failures()) and the node runs on.

#include <cstddef>
#include <string>
#include <vector>

#include "ros2/node_messages.hpp"
#include "ros2/ros_participant.hpp"

namespace lidarcal::ros2 {

/// The QoS of /rosout's writer in rcl: reliable, transient local, keep last 1000, lifespan 10 s.
TopicQos rosoutQos();

class RosoutLogger {
 public:
  /// A writer on /rosout; `logger_name` is the node's logger name (ros2::loggerName). Throws
  /// std::runtime_error when the writer cannot be made.
  RosoutLogger(RosParticipant& participant, std::string logger_name);
  /// Publishes one line.
  void log(const LogRecord& record);
  std::size_t failures() const { return failures_; }  ///< writes that failed

 private:
  int writer_ = 0;
  std::string name_;
  std::size_t failures_ = 0;
};

class DiagnosticsPublisher {
 public:
  /// A writer of DiagnosticArray on `resolved_topic` (default /diagnostics). Throws
  /// std::runtime_error when the writer cannot be made.
  explicit DiagnosticsPublisher(RosParticipant& participant,
                                const std::string& resolved_topic = "/diagnostics");
  /// Publishes the entries as one DiagnosticArray stamped `stamp`, in the order given.
  void publish(const RosTime& stamp, const std::vector<DiagnosticEntry>& entries);
  std::size_t failures() const { return failures_; }  ///< writes that failed

 private:
  int writer_ = 0;
  std::size_t failures_ = 0;
};

class TextPublisher {
 public:
  /// A writer of std_msgs/msg/String on `resolved_topic` (an absolute ROS name, e.g.
  /// resolveTopic(kCandidateModelTopic, parameters)). Throws std::runtime_error when the writer
  /// cannot be made.
  TextPublisher(RosParticipant& participant, const std::string& resolved_topic,
                const TopicQos& qos = latchedQos());
  /// Publishes `text` (UTF-8; must not contain NUL, which ends a CDR string).
  void publish(const std::string& text);
  std::size_t failures() const { return failures_; }  ///< writes that failed

 private:
  int writer_ = 0;
  std::size_t failures_ = 0;
};

}  // namespace lidarcal::ros2
