// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Poses recorded beside the scans (ROS odometry, tf), looked up at each scan's time stamp for
// VIEWPOINT (`lidarcal import --pose odom:TOPIC|tf:FRAME`). Pure geometry, no ROS types: the
// bag reader fills these from nav_msgs/Odometry and tf2_msgs/TFMessage.

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "common/pose2.hpp"
#include "io/stamped_track.hpp"

namespace lidarcal::io {

/// A rigid transform child -> parent: p_parent = rotation * p_child + translation.
struct Transform3 {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();         ///< metres
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< unit quaternion

  Transform3 operator*(const Transform3& b) const {
    return {translation + rotation * b.translation, rotation * b.rotation};
  }
};

/// The planar pose of a frame: position (x, y) and the heading of its x axis projected on the
/// parent's x-y plane.
Pose2 planarPose(const Transform3& t);
/// True when the frame's z axis points down in the parent (a sensor mounted upside down: its
/// beams run clockwise in the parent's plane, which a planar VIEWPOINT cannot express).
bool isUpsideDown(const Transform3& t);

/// Linear in position, slerp in rotation.
struct TransformLerp {
  static Transform3 lerp(const Transform3& a, const Transform3& b, double u) {
    return {a.translation + u * (b.translation - a.translation), a.rotation.slerp(u, b.rotation)};
  }
};

/// Transforms of one frame over time (sorted by stamp), interpolated linearly in position and by
/// slerp in rotation.
using TransformTrack = StampedTrack<Transform3, TransformLerp>;

/// A tf tree: static transforms (/tf_static) and tracks over time (/tf), edge parent -> child.
class TransformTree {
 public:
  void addStatic(const std::string& parent, const std::string& child, const Transform3& t);
  void addDynamic(const std::string& parent, const std::string& child, double stamp_s,
                  const Transform3& t);
  /// The pose of `frame` in `fixed` at `stamp_s` (chain of child -> parent edges from `frame` up
  /// to `fixed`). Without a pose, `why` receives the reason (frame not connected to `fixed`, or
  /// `stamp_s` outside an edge's recorded span by more than `hold_s`).
  std::optional<Transform3> lookup(const std::string& fixed, const std::string& frame,
                                   double stamp_s, double hold_s, std::string* why = nullptr) const;
  /// TransformTrack::keepWithin on every dynamic edge.
  void keepWithin(double window_s, std::size_t max_samples);
  /// Frames known (parents and children), sorted, for messages.
  std::vector<std::string> frames() const;
  /// The frame a sensor `frame` rides on: the one just below the first dynamic (/tf) link met
  /// walking up from `frame`, or the top of its chain when every link is static.
  std::string vehicleFrameOf(const std::string& frame) const;

 private:
  struct Edge {
    std::string parent;
    std::optional<Transform3> fixed;  ///< static edge
    TransformTrack track;             ///< dynamic edge
  };
  std::map<std::string, Edge> parent_of_;  ///< child -> edge to its parent
};

/// Holds the pose while the sensor stands still: a pose within `tolerance_m` and `tolerance_rad`
/// of the held one is replaced by it, so the scans of a stop share one VIEWPOINT (the stop's
/// first pose) and `lidarcal` sees stops.
class StillPoseFilter {
 public:
  StillPoseFilter(double tolerance_m, double tolerance_rad)
      : tol_m_(tolerance_m), tol_rad_(tolerance_rad) {}
  Pose2 apply(const Pose2& p);
  std::size_t stops() const { return stops_; }  ///< distinct poses handed out so far

 private:
  double tol_m_, tol_rad_;
  std::optional<Pose2> held_;
  std::size_t stops_ = 0;
};

}  // namespace lidarcal::io
