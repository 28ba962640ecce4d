// SPDX-License-Identifier: BSD-3-Clause
#include "io/pose_track.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <set>

namespace lidarcal::io {

Pose2 planarPose(const Transform3& t) {
  const Eigen::Vector3d x_axis = t.rotation * Eigen::Vector3d::UnitX();
  return {t.translation.x(), t.translation.y(), std::atan2(x_axis.y(), x_axis.x())};
}

bool isUpsideDown(const Transform3& t) { return (t.rotation * Eigen::Vector3d::UnitZ()).z() < 0.0; }

void TransformTree::addStatic(const std::string& parent, const std::string& child,
                              const Transform3& t) {
  Edge& e = parent_of_[child];
  e.parent = parent;
  e.fixed = t;
}

void TransformTree::addDynamic(const std::string& parent, const std::string& child, double stamp_s,
                               const Transform3& t) {
  Edge& e = parent_of_[child];
  // re-parented: the last parent wins (tf does the same)
  if (e.parent != parent) e.track = TransformTrack();
  e.parent = parent;
  e.track.add(stamp_s, t);
}

std::optional<Transform3> TransformTree::lookup(const std::string& fixed, const std::string& frame,
                                                double stamp_s, double hold_s,
                                                std::string* why) const {
  Transform3 pose;  // frame -> current
  std::string current = frame;
  for (std::size_t depth = 0; current != fixed; ++depth) {
    const auto it = parent_of_.find(current);
    if (it == parent_of_.end() || depth > parent_of_.size()) {
      if (why)
        *why = "frame '" + frame + "' is not connected to '" + fixed + "' (the chain ends at '" +
               current + "')";
      return std::nullopt;
    }
    const Edge& e = it->second;
    const std::optional<Transform3> step = e.track.empty() ? e.fixed : e.track.at(stamp_s, hold_s);
    if (!step) {
      if (why) {
        const auto [first, last] = e.track.span();
        char text[160];
        std::snprintf(text, sizeof text,
                      "at %.3f s: the transform %s -> %s is recorded from %.3f to %.3f s only",
                      stamp_s, e.parent.c_str(), current.c_str(), first, last);
        *why = text;
      }
      return std::nullopt;
    }
    pose = *step * pose;
    current = e.parent;
  }
  return pose;
}

void TransformTree::keepWithin(double window_s, std::size_t max_samples) {
  for (auto& [child, e] : parent_of_) e.track.keepWithin(window_s, max_samples);
}

std::vector<std::string> TransformTree::frames() const {
  std::set<std::string> names;
  for (const auto& [child, e] : parent_of_) {
    names.insert(child);
    names.insert(e.parent);
  }
  return {names.begin(), names.end()};
}

std::string TransformTree::vehicleFrameOf(const std::string& frame) const {
  std::string current = frame;
  for (std::size_t depth = 0; depth <= parent_of_.size(); ++depth) {
    const auto it = parent_of_.find(current);
    if (it == parent_of_.end() || !it->second.track.empty()) return current;
    current = it->second.parent;
  }
  return current;
}

Pose2 StillPoseFilter::apply(const Pose2& p) {
  if (held_ && std::hypot(p.x_m - held_->x_m, p.y_m - held_->y_m) <= tol_m_ &&
      std::abs(wrapAngle(p.yaw_rad - held_->yaw_rad)) <= tol_rad_)
    return *held_;
  held_ = p;
  ++stops_;
  return p;
}

}  // namespace lidarcal::io
