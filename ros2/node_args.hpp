// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The command line of lidarcal_ros2_node, as a ROS 2 executable takes it:
//
//   lidarcal_ros2_node [--help] --ros-args -p model:=M.json [-p input:=scan] [-p
//                      output:=scan_corrected] [-p inversion:=ls|ml] [-p outside:=POLICY] [-p
//                      sensor_name:=NAME] [-p force:=true] [-p input_qos:=sensor_data|default] [-p
//                      output_qos:=sensor_data|default] [-p ros_distro:=humble|jazzy|...] [-p
//                      pose:=odom:TOPIC|tf:FRAME] [-p mode:=apply|watch|learn] [-p
//                      false_alarms:=0.1] [-p false_alarms_per:=km|hour] [-p check_every:=3] [-p
//                      landmark_radius:=R] [-p candidate_topic:=~/candidate_model] [-p
//                      candidate_file:=PATH] [-p diagnostics_period:=1] [-r __node:=NAME] [-r
//                      __ns:=/NS] [-r FROM:=TO]
//
// `--param` and `--remap` are the long forms of -p and -r; `--` ends the ROS arguments. Topic
// names resolve as ROS 2 resolves them (relative to the namespace; `~/x` under the node's name)
// and then go through the remapping rules; the DDS topic is "rt" + the resolved name. The domain
// comes from ROS_DOMAIN_ID (0 when unset), as for any ROS 2 node. No printing here.

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace lidarcal::ros2 {

/// The default topic of the candidate model (a ROS name, resolved under the node's name).
inline constexpr const char* kCandidateModelTopic = "~/candidate_model";

/// What the node does beside correcting (parameter `mode`).
enum class NodeMode {
  apply,  ///< corrects with the model given; no watcher, no pose input (default)
  watch,  ///< corrects with the model given and checks it against the poles as the robot drives
  learn,  ///< also refits after an alarm and switches; without a model, learns one first
};
const char* toString(NodeMode m);

/// The QoS profiles of ROS 2 (rmw_qos_profile_sensor_data, rmw_qos_profile_default).
enum class QosProfile {
  sensor_data,  ///< best effort, keep last 5, volatile: matches every publisher
  /// ROS 2's default profile: reliable, keep last 10, volatile: matches every subscriber
  reliable,
};
const char* toString(QosProfile q);

/// The ROS 2 release of the other nodes on the domain. It decides the layout of what the node
/// announces on `ros_discovery_info`: a GID is 24 bytes up to Humble and 16 bytes from Iron on
/// (rmw_dds_common: rmw_dds_common/msg/Gid.msg on the branches humble and iron).
enum class RosDistro { foxy, galactic, humble, iron, jazzy, kilted, rolling };
const char* toString(RosDistro d);
/// The length of a GID on the wire in that release: 24 or 16 bytes.
std::size_t gidBytes(RosDistro d);

/// Where the vehicle's poses come from (parameter `pose`), as `lidarcal import --pose`.
struct PoseSource {
  enum class Kind {
    /// nav_msgs/msg/Odometry on `name`, composed with the sensor's mount from /tf_static
    odom,
    /// the chain from the fixed frame `name` to the scan's frame_id through /tf and /tf_static
    tf,
  };
  Kind kind = Kind::odom;     ///< default odom
  std::string name = "odom";  ///< odom: the topic (a ROS name, default odom); tf: the fixed frame
};

struct NodeParameters {
  /// model: model.json (a sensor's or a rig's) or export's YAML (required; may be empty in mode
  /// learn only)
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
  /// ros_distro: the other nodes' ROS 2 release (default humble): the GID layout announced
  RosDistro ros_distro = RosDistro::humble;
  /// pose: odom:TOPIC | tf:FRAME (default odom:odom); read by the watch modes, not by apply
  PoseSource pose;
  NodeMode mode = NodeMode::apply;  ///< mode: apply (default), watch or learn
  /// false_alarms: alarms expected per unit of exposure while the model holds (> 0); unset: the
  /// watcher's default, 0.1 (watch::FalseAlarmRate). Read in watch and learn modes.
  std::optional<double> false_alarms;
  /// false_alarms_per: the exposure counted, "km" travelled (false, default) or "hour" of
  /// driving (true)
  bool false_alarms_per_hour = false;
  /// check_every: metres of travel between two checks (> 0); unset: the watcher's default, 3 m
  std::optional<double> check_every_m;
  /// check_bias_replicas: replicas that estimate a check fit's own bias, for the checks tested
  /// against zero (0..100; 0: none); unset: the watcher's default, 4
  std::optional<int> check_bias_replicas;
  /// landmark_radius: the poles' radius in metres (> 0); unset (or given empty): estimated with
  /// the bias
  std::optional<double> landmark_radius_m;
  /// candidate_topic: where learn mode publishes each refit's model as JSON (ROS name)
  std::string candidate_topic = kCandidateModelTopic;
  /// candidate_file: learn mode also writes each refit's model there, atomically (its directory
  /// must exist); unset (or given empty): no file
  std::optional<std::string> candidate_file;
  /// diagnostics_period: seconds between two DiagnosticArray messages (> 0; default 1)
  double diagnostics_period_s = 1.0;
  /// -r __node:=NAME (letters, digits, '_'; not starting with a digit)
  std::string node_name = "lidarcal";
  std::string node_namespace = "/";  ///< -r __ns:=/NS (absolute; tokens as node names)
  std::vector<std::pair<std::string, std::string>> remaps;  ///< -r FROM:=TO for topics, in order
  bool help = false;  ///< --help or -h was given: print nodeHelp() and exit 0
};

/// Parses argv (argv[0] skipped). Throws InputError naming the argument and the remedy for an
/// unknown parameter, a malformed -p/-r, a bad value, or a missing model (unless help; the model
/// may be left out in mode learn only).
NodeParameters parseNodeArguments(int argc, const char* const* argv);

/// The parameters and their defaults, for --help.
std::string nodeHelp();

/// A topic name resolved against the node's namespace and name (ROS 2 rules), then remapped:
/// "scan" -> "/NS/scan", "~/x" -> "/NS/NODE/x", "/abs" unchanged. Throws InputError for a name
/// ROS 2 would refuse (empty, with characters other than alphanumerics, '_', '/', '~').
std::string resolveTopic(const std::string& name, const NodeParameters& p);

/// The node's fully qualified name: "/NS/NAME" ("/NAME" in the root namespace).
std::string fullyQualifiedNodeName(const NodeParameters& p);
/// The node's logger name as rcl makes it (rcl: rcl/src/rcl/node.c): the namespace without its
/// leading '/', its '/' replaced by '.', then '.' and the node's name ("NAME" in the root
/// namespace; "robot1.NAME" in "/robot1").
std::string loggerName(const NodeParameters& p);

/// `-p pose:=` parsed: "odom:TOPIC" or "tf:FRAME" (a frame's leading '/' removed). Throws
/// InputError naming the parameter for anything else.
PoseSource parsePoseSource(const std::string& text);
/// `-p mode:=` parsed. Throws InputError naming the modes.
NodeMode parseNodeMode(const std::string& text);
/// `-p ros_distro:=` parsed (the release's name in lower case). Throws InputError listing the
/// names known.
RosDistro parseRosDistro(const std::string& text);

/// The DDS topic of a resolved ROS 2 topic: "rt" + name ("/scan" -> "rt/scan").
std::string ddsTopicName(const std::string& resolved);

/// ROS_DOMAIN_ID from the environment (0 when unset or empty). Throws InputError when it is not
/// an integer in 0..232 (the RTPS port mapping's range).
int domainIdFromEnvironment();

}  // namespace lidarcal::ros2
