// SPDX-License-Identifier: BSD-3-Clause
#include "io/wheel_track.hpp"

#include <algorithm>
#include <cmath>

#include "common/errors.hpp"

namespace lidarcal::io {

WheelJoints WheelJoints::parse(const std::string& text, const std::string& option) {
  const std::size_t colon = text.rfind(':');
  const std::size_t comma = text.find(',', colon == std::string::npos ? 0 : colon);
  WheelJoints j;
  if (colon != std::string::npos && comma != std::string::npos) {
    j.topic = text.substr(0, colon);
    j.left = text.substr(colon + 1, comma - colon - 1);
    j.right = text.substr(comma + 1);
  }
  if (j.topic.empty() || j.left.empty() || j.right.empty() || j.left == j.right)
    throw InputError("", option + " " + text, "is not TOPIC:LEFT_JOINT,RIGHT_JOINT",
                     "e.g. /joint_states:left_wheel_joint,right_wheel_joint (sensor_msgs/"
                     "JointState; `ros2 topic echo --once /joint_states` names the joints)");
  return j;
}

void WheelTrack::addMessage(double stamp_s, const std::vector<std::string>& names,
                            const std::vector<double>& positions, const WheelJoints& joints) {
  const auto index = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  const std::size_t l = index(joints.left), r = index(joints.right);
  if (l >= positions.size() || r >= positions.size() || !std::isfinite(stamp_s) ||
      !std::isfinite(positions[l]) || !std::isfinite(positions[r])) {
    for (const std::string& n : names)
      if (std::find(names_seen_.begin(), names_seen_.end(), n) == names_seen_.end() &&
          names_seen_.size() < 20)
        names_seen_.push_back(n);
    return;
  }
  samples_.add(stamp_s, Eigen::Vector2d(positions[l], positions[r]));
}

std::optional<std::pair<double, double>> WheelTrack::at(double stamp_s) const {
  const std::optional<Eigen::Vector2d> angles = samples_.at(stamp_s, 0.0);  // nothing outside
  if (!angles) return std::nullopt;
  return std::pair{(*angles)[0], (*angles)[1]};
}

void WheelTrack::checkFilled(const std::filesystem::path& file, const WheelJoints& joints) const {
  if (!samples_.empty()) return;
  std::string seen;
  for (const std::string& n : names_seen_) seen += (seen.empty() ? "" : ", ") + n;
  throw InputError(
      file.string(), "topic " + joints.topic,
      "has no message with both joints " + joints.left + " and " + joints.right +
          (seen.empty() ? std::string(" (no joint state at all)") : " (joints seen: " + seen + ")"),
      "name the wheel joints as the robot's controller publishes them");
}

}  // namespace lidarcal::io
