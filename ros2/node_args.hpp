// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The command line of lidarcal_ros2_node, as a ROS 2 executable takes it:
//
//   lidarcal_ros2_node [--help] --ros-args -p model:=M.json [-p input:=scan] [-p
//                      output:=scan_corrected] [-p inversion:=ls|ml] [-p outside:=POLICY] [-p
//                      sensor_name:=NAME] [-p force:=true] [-p input_qos:=sensor_data|default] [-p
//                      output_qos:=sensor_data|default] [-r __node:=NAME] [-r __ns:=/NS] [-r
//                      FROM:=TO]
//
// `--param` and `--remap` are the long forms of -p and -r; `--` ends the ROS arguments. Topic
// names resolve as ROS 2 resolves them (relative to the namespace; `~/x` under the node's name)
// and then go through the remapping rules; the DDS topic is "rt" + the resolved name. The domain
// comes from ROS_DOMAIN_ID (0 when unset), as for any ROS 2 node. No printing here.

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace lidarcal::ros2 {

/// The QoS profiles of ROS 2 (rmw_qos_profile_sensor_data, rmw_qos_profile_default).
enum class QosProfile {
  sensor_data,  ///< best effort, keep last 5, volatile: matches every publisher
  /// ROS 2's default profile: reliable, keep last 10, volatile: matches every subscriber
  reliable,
};
const char* toString(QosProfile q);

struct NodeParameters {
  /// model: model.json (a sensor's or a rig's) or export's YAML (required)
  std::string model_file;
  std::string input = "scan";             ///< input: LaserScan topic to correct (ROS name)
  std::string output = "scan_corrected";  ///< output: topic of the corrected scans (ROS name)
  std::optional<std::string> inversion;   ///< inversion: ls | ml; unset: the YAML's, else ls
  /// outside: a policy name of `correct --outside`; unset: the YAML's, else the default
  std::optional<std::string> outside;
  /// sensor_name: refused at start when not the model's; unset: not checked. With a rig model: the
  /// block to apply (name, topic or frame); unset: the block whose topic is the resolved input.
  std::optional<std::string> sensor_name;
  bool force = false;  ///< force: apply a model whose range limits differ from the scans'
  QosProfile input_qos = QosProfile::sensor_data;  ///< input_qos: sensor_data (default) or default
  QosProfile output_qos = QosProfile::reliable;    ///< output_qos: default (default) or sensor_data
  std::string node_name = "lidarcal";              ///< -r __node:=NAME
  std::string node_namespace = "/";                ///< -r __ns:=/NS (absolute)
  std::vector<std::pair<std::string, std::string>> remaps;  ///< -r FROM:=TO for topics, in order
  bool help = false;  ///< --help or -h was given: print nodeHelp() and exit 0
};

/// Parses argv (argv[0] skipped). Throws InputError naming the argument and the remedy for an
/// unknown parameter, a malformed -p/-r, a bad value, or a missing model (unless help).
NodeParameters parseNodeArguments(int argc, const char* const* argv);

/// The parameters and their defaults, for --help.
std::string nodeHelp();

/// A topic name resolved against the node's namespace and name (ROS 2 rules), then remapped:
/// "scan" -> "/NS/scan", "~/x" -> "/NS/NODE/x", "/abs" unchanged. Throws InputError for a name
/// ROS 2 would refuse (empty, with characters other than alphanumerics, '_', '/', '~').
std::string resolveTopic(const std::string& name, const NodeParameters& p);

/// The DDS topic of a resolved ROS 2 topic: "rt" + name ("/scan" -> "rt/scan").
std::string ddsTopicName(const std::string& resolved);

/// ROS_DOMAIN_ID from the environment (0 when unset or empty). Throws InputError when it is not
/// an integer in 0..232 (the RTPS port mapping's range).
int domainIdFromEnvironment();

}  // namespace lidarcal::ros2
