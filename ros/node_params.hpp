// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The private parameters of lidarcal_node, read once at start and checked: a value of the wrong
// type or out of range is refused (InputError naming the parameter and the remedy; the node
// exits 2). The watcher's parameters map onto watch::WatchSettings in watchSettingsFrom().

#include <optional>
#include <string>

#include "ros2/node_args.hpp"
#include "watch/watch_settings.hpp"

namespace ros {
class NodeHandle;
}

namespace lidarcal::ros1 {

/// What the node does beside correcting (~mode): the ROS 2 node's modes, the same three.
using NodeMode = ros2::NodeMode;
using ros2::toString;

/// The watcher's parameters (read in every mode; used in watch and learn).
struct WatchParameters {
  NodeMode mode = NodeMode::apply;  ///< ~mode: apply (default) | watch | learn
  /// ~false_alarms: expected false alarms per unit of ~false_alarms_per while the model holds;
  /// default 0.1
  double false_alarms = watch::FalseAlarmRate{}.per_unit;
  /// ~false_alarms_per: km (default) | hour (of driving)
  watch::Exposure false_alarms_per = watch::Exposure::distance;
  double check_every_m = watch::CheckSettings{}.every_m;  ///< ~check_every: metres; default 3
  std::optional<double> landmark_radius_m;  ///< ~landmark_radius: metres; unset: estimated
  /// ~check_bias_replicas: replicas for a check fit's own bias (0..100; 0: none)
  int check_bias_replicas = watch::CheckSettings{}.bias_replicas;
  /// ~pose: odom:TOPIC (nav_msgs/Odometry; default odom:/odom) | tf:FIXED_FRAME
  ros2::PoseSource pose{ros2::PoseSource::Kind::odom, "/odom"};
  /// ~candidate_topic: where learn mode publishes each refit (std_msgs/String, latched);
  /// default ~candidate_model
  std::string candidate_topic = "~candidate_model";
  std::string candidate_file;         ///< ~candidate_file: also written there; default "" (none)
  double diagnostics_period_s = 1.0;  ///< ~diagnostics_period: seconds; default 1
};

/// All the node's parameters.
struct NodeSettings {
  /// ~model: model.json or export's YAML; required but in learn mode ("" when not given)
  std::string model_file;
  std::string input = "scan";             ///< ~input: LaserScan topic to read
  std::string output = "scan_corrected";  ///< ~output: topic of the corrected scans
  std::optional<std::string> inversion;   ///< ~inversion: ls | ml; unset: the YAML's, else ls
  /// ~outside: a policy of `correct --outside`; unset: the YAML's, else correct's default
  std::optional<std::string> outside;
  std::optional<std::string> sensor_name;  ///< ~sensor_name: checked against the model at start
  bool force = false;     ///< ~force: apply a model whose range limits differ from the scans'
  WatchParameters watch;  ///< the watcher's
};

/// Reads the private parameters through `pnh` (the node's private handle). Throws InputError
/// for a value of the wrong type, out of range, or a missing ~model outside learn mode.
NodeSettings readNodeSettings(const ros::NodeHandle& pnh);

/// The watcher's settings for watch and learn modes: watch::defaultWatchSettings() with the
/// parameters applied.
watch::WatchSettings watchSettingsFrom(const WatchParameters& p);

/// The parameters with their defaults, for --help.
std::string nodeHelp();

}  // namespace lidarcal::ros1
