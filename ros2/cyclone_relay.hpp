// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The scan path of lidarcal_ros2_node, on Eclipse Cyclone DDS: a reader of the input topic and a
// writer of the output topic on the node's participant (ros2/ros_participant.hpp, which names the
// node as their owner on the graph), both of type sensor_msgs::msg::dds_::LaserScan_ (generated
// by idlc from ros2/idl/LaserScan.idl) in plain CDR (XCDR version 1), with the QoS profiles ROS 2
// names. A received scan is handed to the caller, changed in place and written as it is: header
// and intensities go out as they came in.

#include <cstddef>
#include <functional>
#include <string>

#include "ros2/node_args.hpp"
#include "ros2/ros_participant.hpp"

struct sensor_msgs_msg_dds__LaserScan_;

namespace lidarcal::ros2 {

struct RelayConfig {
  std::string input_topic = "rt/scan";             // DDS topic read
  std::string output_topic = "rt/scan_corrected";  // DDS topic written
  QosProfile input_qos = QosProfile::sensor_data;  // reader QoS
  QosProfile output_qos = QosProfile::reliable;    // writer QoS
};

/// Return true to publish the (changed) scan, false to drop it.
using ScanHandler = std::function<bool(sensor_msgs_msg_dds__LaserScan_& scan)>;

class CycloneRelay {
 public:
  /// Creates the reader and writer on `participant` (which must outlive the relay). Throws
  /// std::runtime_error naming the DDS call that failed and Cyclone's reason.
  CycloneRelay(RosParticipant& participant, const RelayConfig& config);
  ~CycloneRelay();
  CycloneRelay(const CycloneRelay&) = delete;
  CycloneRelay& operator=(const CycloneRelay&) = delete;

  /// Waits at most `timeout_s` for scans, then hands each received one to `handler` in arrival
  /// order and writes those it accepts. Returns the number of scans handed on.
  std::size_t spinOnce(double timeout_s, const ScanHandler& handler);

 private:
  int reader_ = 0, writer_ = 0, waitset_ = 0;  // dds_entity_t handles
};

}  // namespace lidarcal::ros2
