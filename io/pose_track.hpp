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

/// Transforms of one frame over time (sorted by stamp), interpolated linearly in position and by
/// slerp in rotation.
class TransformTrack {
 public:
  /// Adds a sample; stamps may come in any order (sorted on first lookup).
  void add(double stamp_s, const Transform3& t);
  bool empty() const { return samples_.empty(); }
  std::size_t size() const { return samples_.size(); }
  /// Stamp range [first, last], seconds. Undefined when empty.
  std::pair<double, double> span() const;
  /// The transform at `stamp_s`: interpolated between the samples around it; the nearest end
  /// sample within `hold_s` outside the span; nothing further out.
  std::optional<Transform3> at(double stamp_s, double hold_s) const;
  /// Forgets the samples stamped more than `window_s` before the newest one, keeping the last of
  /// them (so a stamp inside the window still interpolates), and then all but the newest
  /// `max_samples` (at least 2 kept). For a live stream, whose past must not grow without bound.
  void keepWithin(double window_s, std::size_t max_samples);

 private:
  void sort() const;
  mutable std::vector<std::pair<double, Transform3>> samples_;
  mutable bool sorted_ = true;
};

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
