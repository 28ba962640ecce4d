// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What the node says on the ROS 2 graph besides its scans, as plain structs without DDS: a log
// line for /rosout (rcl_interfaces/msg/Log), a component's state for /diagnostics
// (diagnostic_msgs/msg/DiagnosticStatus) and a time stamp (builtin_interfaces/msg/Time). The
// publishers that put them on the wire are in ros2/node_outputs.hpp; a library that decides what
// to report fills these and needs no DDS.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace lidarcal::ros2 {

/// builtin_interfaces/msg/Time: seconds and nanoseconds since the epoch of the clock used.
struct RosTime {
  std::int32_t sec = 0;       ///< seconds
  std::uint32_t nanosec = 0;  ///< nanoseconds added to sec, [0, 1e9)
  double seconds() const { return static_cast<double>(sec) + 1e-9 * static_cast<double>(nanosec); }
};
/// The system clock now, as rcl stamps a log line.
RosTime wallClockNow();
/// A time in seconds as a RosTime (nanoseconds rounded; negative times floor to the second below).
RosTime rosTimeFromSeconds(double seconds);

/// Severity of a log line: the constants of rcl_interfaces/msg/Log.msg.
enum class LogLevel : std::uint8_t { debug = 10, info = 20, warn = 30, error = 40, fatal = 50 };

/// Where a log line was written from, as rclcpp's logging macros fill it.
struct LogOrigin {
  const char* file = "";      ///< source file (__FILE__)
  const char* function = "";  ///< function (__func__)
  std::uint32_t line = 0;     ///< line in `file` (__LINE__)
};
/// The origin of the line this macro stands on.
#define LIDARCAL_LOG_ORIGIN \
  ::lidarcal::ros2::LogOrigin { __FILE__, __func__, static_cast<std::uint32_t>(__LINE__) }

/// One line for /rosout; the logger's name is the node's (RosoutLogger adds it).
struct LogRecord {
  RosTime stamp;                    ///< when it was written (default: the epoch)
  LogLevel level = LogLevel::info;  ///< severity (default info)
  std::string msg;                  ///< the text, without a trailing newline
  LogOrigin origin;                 ///< where in the source it was written (default: nowhere)
};

/// Level of a component's state: the constants of diagnostic_msgs/msg/DiagnosticStatus.msg.
enum class DiagnosticLevel : std::uint8_t { ok = 0, warn = 1, error = 2, stale = 3 };

/// One component's state on /diagnostics (diagnostic_msgs/msg/DiagnosticStatus).
struct DiagnosticEntry {
  DiagnosticLevel level = DiagnosticLevel::ok;  ///< default ok
  std::string name;         ///< the component, e.g. "lidarcal: range model" (required)
  std::string message;      ///< its state in a few words
  std::string hardware_id;  ///< the hardware it concerns, e.g. the sensor's name; default ""
  /// measurements as key and text value, in the order given
  std::vector<std::pair<std::string, std::string>> values;
};

}  // namespace lidarcal::ros2
