// SPDX-License-Identifier: BSD-3-Clause
#include "ros2/live_poses.hpp"

#include <cmath>

namespace lidarcal::ros2 {
namespace {

io::BagPoseConfig bagConfig(const LivePoseSettings& s) {
  io::BagPoseConfig c;
  c.kind = s.source.kind == PoseSource::Kind::odom ? io::BagPoseConfig::Kind::odom
                                                   : io::BagPoseConfig::Kind::tf;
  c.name = s.source.name;
  c.hold_s = s.hold_s;
  return c;
}

io::Transform3 transformOf(const ReceivedTransform& t) {
  return io::makeTransform({t.x, t.y, t.z}, Eigen::Quaterniond(t.qw, t.qx, t.qy, t.qz));
}

}  // namespace

const char* toString(PoseDropReason r) {
  switch (r) {
    case PoseDropReason::bad_stamp:
      return "a stamp that is unset or not a time";
    case PoseDropReason::empty_frame:
      return "an empty frame name";
    case PoseDropReason::self_transform:
      return "a frame's transform to itself";
    case PoseDropReason::non_finite:
      return "a translation or rotation that is not finite";
    case PoseDropReason::count_:
      break;
  }
  return "?";
}

std::size_t LivePoseStats::droppedTotal() const {
  std::size_t n = 0;
  for (std::size_t d : dropped) n += d;
  return n;
}

LivePoses::LivePoses(const LivePoseSettings& settings)
    : settings_(settings), poses_(bagConfig(settings)) {}

std::optional<PoseDropReason> LivePoses::check(const ReceivedTransform& t, bool is_static) {
  std::optional<PoseDropReason> r;
  const std::string parent = io::stripSlash(t.parent), child = io::stripSlash(t.child);
  // A static transform holds at any time (tf ignores its stamp); a moving one needs its stamp.
  const bool unset = t.stamp.sec < 0 || (t.stamp.sec == 0 && t.stamp.nanosec == 0);
  if (t.stamp.nanosec >= 1000000000u || (unset && !is_static))
    r = PoseDropReason::bad_stamp;
  else if (parent.empty() || child.empty())
    r = PoseDropReason::empty_frame;
  else if (parent == child)
    r = PoseDropReason::self_transform;
  else
    for (double v : {t.x, t.y, t.z, t.qx, t.qy, t.qz, t.qw})
      if (!std::isfinite(v)) r = PoseDropReason::non_finite;
  if (r) ++stats_.dropped[static_cast<std::size_t>(*r)];
  return r;
}

std::optional<PoseDropReason> LivePoses::addOdometry(const ReceivedTransform& t) {
  if (settings_.source.kind != PoseSource::Kind::odom) return std::nullopt;
  if (const auto r = check(t, false)) return r;
  poses_.addOdometry(t.stamp.seconds(), transformOf(t), t.child);
  odom_frame_ = io::stripSlash(t.parent);
  poses_.keepWithin(settings_.window_s, settings_.max_samples);
  ++stats_.odometry;
  return std::nullopt;
}

std::optional<PoseDropReason> LivePoses::addTransform(const ReceivedTransform& t, bool is_static) {
  if (const auto r = check(t, is_static)) return r;
  poses_.addTransform(t.parent, t.child, t.stamp.seconds(), transformOf(t), is_static);
  if (!is_static) poses_.keepWithin(settings_.window_s, settings_.max_samples);
  ++stats_.transforms;
  return std::nullopt;
}

PoseLookup LivePoses::at(const std::string& frame, const RosTime& stamp) {
  PoseLookup out;
  const bool odom = settings_.source.kind == PoseSource::Kind::odom;
  out.fixed_frame = odom ? odom_frame_ : settings_.source.name;
  const std::string child = io::stripSlash(frame);
  if (child.empty()) {
    out.why = "the scan has no frame_id";
    return out;
  }
  if (const auto t = poses_.at(child, stamp.seconds(), out.why, &out.mount_missing))
    out.pose = io::planarPose(*t);
  return out;
}

}  // namespace lidarcal::ros2
