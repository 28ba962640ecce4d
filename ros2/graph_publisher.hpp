// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The writer of `ros_discovery_info`: rmw_dds_common/msg/ParticipantEntitiesInfo with this
// participant's GID and one entry per node (namespace, name, the GIDs of its readers and
// writers), as rmw_cyclonedds_cpp publishes it (rmw_cyclonedds: rmw_cyclonedds_cpp/src/
// rmw_node.cpp): DDS topic "ros_discovery_info" without the "rt" prefix, QoS reliable,
// transient local, keep last 1 (latchedQos()). A GID is the entity's 16-byte DDS GUID, zero padded
// to the release's GID length (24 bytes up to Humble, 16 from Iron on).

#include "ros2/ros_participant.hpp"

namespace lidarcal::ros2 {

/// The DDS topic of the graph announcements.
inline constexpr const char* kDiscoveryTopic = "ros_discovery_info";

/// ParticipantEntitiesInfo in the layout of `distro`, under its ROS 2 type name
/// rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_ (both layouts share it).
const dds_topic_descriptor& participantEntitiesInfoType(RosDistro distro);

class GraphPublisher {
 public:
  /// A writer of ros_discovery_info on `participant` (dds_entity_t) in the layout of `distro`.
  /// Throws std::runtime_error when Cyclone refuses.
  GraphPublisher(int participant, RosDistro distro);

  /// Writes the participant's GID and the one node's entry. Throws std::runtime_error when the
  /// write fails.
  void publish(const Guid& participant, const NodeEntities& node) const;

 private:
  int writer_ = 0;
  RosDistro distro_;
};

}  // namespace lidarcal::ros2
