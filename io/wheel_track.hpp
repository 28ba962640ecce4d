// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The wheels' angles recorded beside the scans (sensor_msgs/JointState positions, as a
// differential-drive controller publishes them), looked up at each scan's stamp for
// wheel_angles.csv (`lidarcal import --wheels TOPIC:LEFT,RIGHT`). No ROS types: the bag readers
// fill it.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "io/stamped_track.hpp"

namespace lidarcal::io {

/// Which JointState topic and which two of its joints are the wheels.
struct WheelJoints {
  std::string topic;  ///< empty: no wheels read
  std::string left, right;
  bool enabled() const { return !topic.empty(); }
  /// Parses TOPIC:LEFT,RIGHT; throws InputError naming `option` when it is not of that form.
  static WheelJoints parse(const std::string& text, const std::string& option);
};

/// Both wheels' angles over time (sorted by stamp), interpolated linearly.
class WheelTrack {
 public:
  /// Reads one message's joints: its stamp, names and positions. Messages without both wheels
  /// (another controller's joints on the same topic) are skipped.
  void addMessage(double stamp_s, const std::vector<std::string>& names,
                  const std::vector<double>& positions, const WheelJoints& joints);
  bool empty() const { return samples_.empty(); }
  std::size_t size() const { return samples_.size(); }
  /// The angles (left, right, radians) at `stamp_s`: interpolated inside the recorded span,
  /// nothing outside it.
  std::optional<std::pair<double, double>> at(double stamp_s) const;
  /// Throws InputError naming `file`, the topic and the joints seen when no message held both
  /// wheels.
  void checkFilled(const std::filesystem::path& file, const WheelJoints& joints) const;

 private:
  struct Lerp {
    static Eigen::Vector2d lerp(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double u) {
      return (1.0 - u) * a + u * b;
    }
  };
  StampedTrack<Eigen::Vector2d, Lerp> samples_;
  std::vector<std::string> names_seen_;  ///< for the message when the wheels are missing
};

}  // namespace lidarcal::io
