// SPDX-License-Identifier: BSD-3-Clause
#include "ros2/node_args.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "calibration/filtering.hpp"
#include "common/errors.hpp"
#include "watch/watch_settings.hpp"

namespace lidarcal::ros2 {
namespace {

const char* const kUsage = "see lidarcal_ros2_node --help";

/// "name:=value" split at ":="; throws naming the argument when there is none.
std::pair<std::string, std::string> splitAssignment(const std::string& text,
                                                    const std::string& flag) {
  const auto at = text.find(":=");
  if (at == std::string::npos || at == 0)
    throw InputError("", flag + " " + text, "is not NAME:=VALUE", kUsage);
  return {text.substr(0, at), text.substr(at + 2)};
}

/// A parameter value as ROS 2 reads it from the command line (YAML): quotes removed.
std::string unquote(const std::string& v) {
  if (v.size() >= 2 && (v.front() == '"' || v.front() == '\'') && v.back() == v.front())
    return v.substr(1, v.size() - 2);
  return v;
}

bool parseBool(const std::string& name, const std::string& v) {
  if (v == "true" || v == "True" || v == "TRUE") return true;
  if (v == "false" || v == "False" || v == "FALSE") return false;
  throw InputError("", "-p " + name + ":=" + v, "is not a boolean", "use true or false");
}

/// A ROS 2 name token: letters, digits and '_', not starting with a digit (rmw's node name rule).
bool validToken(const std::string& t) {
  if (t.empty() || t.size() > 255 || std::isdigit(static_cast<unsigned char>(t[0]))) return false;
  for (char c : t)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

bool validNamespace(const std::string& ns) {
  if (ns == "/") return true;
  if (ns.size() < 2 || ns[0] != '/' || ns.back() == '/' || ns.size() > 255) return false;
  for (std::size_t at = 1; at < ns.size();) {
    const std::size_t end = std::min(ns.find('/', at), ns.size());
    if (!validToken(ns.substr(at, end - at))) return false;
    at = end + 1;
  }
  return true;
}

/// A number > 0 (finite), as `-p name:=v` gives it; throws naming the parameter and an example.
double parsePositive(const std::string& name, const std::string& v, const char* example) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !std::isfinite(x) || !(x > 0.0))
    throw InputError("", "-p " + name + ":=" + v, "is not a number above 0",
                     std::string("e.g. -p ") + name + ":=" + example);
  return x;
}

/// A whole number in [lo, hi], as `-p name:=v` gives it; throws naming the parameter.
int parseCount(const std::string& name, const std::string& v, int lo, int hi, const char* example) {
  char* end = nullptr;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || x < lo || x > hi)
    throw InputError("", "-p " + name + ":=" + v,
                     "is not a whole number in " + std::to_string(lo) + ".." + std::to_string(hi),
                     std::string("e.g. -p ") + name + ":=" + example);
  return static_cast<int>(x);
}

QosProfile parseQos(const std::string& name, const std::string& v) {
  if (v == "sensor_data") return QosProfile::sensor_data;
  if (v == "default" || v == "reliable") return QosProfile::reliable;
  throw InputError("", "-p " + name + ":=" + v, "is not a QoS profile of this node",
                   "use sensor_data or default");
}

/// The parameters of the watch and learn modes (checked in every mode), and the ones every ROS 2
/// node accepts; anything else is refused.
void setWatchParameter(NodeParameters& p, const std::string& name, const std::string& v,
                       const std::string& raw) {
  if (name == "mode")
    p.mode = parseNodeMode(v);
  else if (name == "false_alarms")
    p.false_alarms = parsePositive(name, v, "0.1");
  else if (name == "false_alarms_per") {
    if (v != "km" && v != "hour")
      throw InputError("", "-p false_alarms_per:=" + v, "is not km or hour",
                       "count false alarms per km travelled (km) or per hour of driving (hour)");
    p.false_alarms_per_hour = v == "hour";
  } else if (name == "check_every")
    p.check_every_m = parsePositive(name, v, "3");
  else if (name == "check_bias_replicas")
    p.check_bias_replicas = parseCount(name, v, 0, 100, "4");
  else if (name == "landmark_radius")  // empty: unset, so that a launch file can pass its default
    p.landmark_radius_m =
        v.empty() ? std::nullopt : std::optional<double>(parsePositive(name, v, "0.05"));
  else if (name == "candidate_topic")
    p.candidate_topic = v;
  else if (name == "candidate_file")
    p.candidate_file = v.empty() ? std::nullopt : std::optional<std::string>(v);
  else if (name == "diagnostics_period")
    p.diagnostics_period_s = parsePositive(name, v, "1");
  // every ROS 2 node accepts it; stamps are copied, not made
  else if (name == "use_sim_time")
    parseBool(name, v);
  else
    throw InputError("", "-p " + name + ":=" + raw, "is not a parameter of lidarcal_ros2_node",
                     kUsage);
}

void setParameter(NodeParameters& p, const std::string& name, const std::string& raw) {
  const std::string v = unquote(raw);
  if (name == "model")
    p.model_file = v;
  else if (name == "input")
    p.input = v;
  else if (name == "output")
    p.output = v;
  else if (name == "inversion")
    p.inversion = v;
  else if (name == "outside")
    p.outside = v;
  else if (name == "sensor_name")
    p.sensor_name = v;
  else if (name == "force")
    p.force = parseBool(name, v);
  else if (name == "input_qos")
    p.input_qos = parseQos(name, v);
  else if (name == "output_qos")
    p.output_qos = parseQos(name, v);
  else if (name == "ros_distro")
    p.ros_distro = parseRosDistro(v);
  else if (name == "pose")
    p.pose = parsePoseSource(v);
  else
    setWatchParameter(p, name, v, raw);
}

void applyRemap(NodeParameters& p, const std::string& from, const std::string& to) {
  if (from == "__node" || from == "__name") {
    if (!validToken(to))
      throw InputError("", "-r " + from + ":=" + to,
                       "is not a ROS 2 node name (letters, digits and '_', not starting with a "
                       "digit)",
                       "e.g. -r __node:=front_lidar");
    p.node_name = to;
  } else if (from == "__ns") {
    if (to.empty() || to[0] != '/')
      throw InputError("", "-r __ns:=" + to, "a namespace must be absolute",
                       "e.g. -r __ns:=/robot1");
    if (!validNamespace(to))
      throw InputError("", "-r __ns:=" + to,
                       "is not a ROS 2 namespace ('/'-separated names of letters, digits and '_')",
                       "e.g. -r __ns:=/robot1");
    p.node_namespace = to;
  } else {
    p.remaps.emplace_back(from, to);
  }
}

bool validTopicName(const std::string& n) {
  if (n.empty()) return false;
  for (char c : n)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/' || c == '~'))
      return false;
  return n.find("//") == std::string::npos && (n.size() == 1 || n.back() != '/');
}

/// The name made absolute, without remapping.
std::string qualify(const std::string& name, const NodeParameters& p) {
  if (!validTopicName(name))
    throw InputError("", "topic '" + name + "'",
                     "is not a valid ROS 2 topic name (letters, digits, '_', '/', a leading '~')",
                     "e.g. -p input:=scan or -p input:=/robot/scan");
  const std::string ns = p.node_namespace == "/" ? "" : p.node_namespace;
  if (name[0] == '/') return name;
  if (name[0] == '~') return ns + "/" + p.node_name + (name.size() > 1 ? name.substr(1) : "");
  return ns + "/" + name;
}

/// The part of --help on the watch and learn modes, with the watcher's defaults.
std::string watchHelp() {
  const watch::WatchSettings d = watch::defaultWatchSettings();
  char text[2400];
  std::snprintf(
      text, sizeof text,
      "  mode         apply (default): correct only; watch: correct and check the model against "
      "the poles passed\n"
      "               (needs poses); learn: also refit after an alarm and switch to the new model "
      "(without a model:\n"
      "               scans pass uncorrected until one is learnt)\n"
      "  false_alarms       alarms expected per unit while the model holds (default %g)\n"
      "  false_alarms_per   km (travelled; default) or hour (of driving)\n"
      "  check_every        metres of travel between two checks (default %g)\n"
      "  check_bias_replicas replicas that estimate a check fit's own bias, for the checks "
      "tested against zero\n"
      "               (0: none; default %d)\n"
      "  landmark_radius    the poles' radius, m (default, or empty: estimated with the bias)\n"
      "  candidate_topic    learn: each refit's model as JSON, std_msgs/msg/String, latched "
      "(default %s)\n"
      "  candidate_file     learn: each refit's model also written to this file, atomically "
      "(default, or empty: none)\n"
      "  diagnostics_period seconds between two messages on /diagnostics (default 1; every "
      "mode)\n",
      d.false_alarms.per_unit, d.check.every_m, d.check.bias_replicas, kCandidateModelTopic);
  return text;
}

/// The checks that need every parameter: the model (optional in learn mode only), the names and
/// policies, the candidate file's directory.
void checkParameters(const NodeParameters& p) {
  if (p.model_file.empty() && p.mode != NodeMode::learn)
    throw InputError("", "parameter model", "is not set",
                     "give this sensor's model: --ros-args -p model:=/path/model.json (only -p "
                     "mode:=learn starts without one)");
  if (p.inversion && *p.inversion != "ls" && *p.inversion != "ml")
    throw InputError("", "-p inversion:=" + *p.inversion, "is not an inversion", "use ls or ml");
  if (p.pose.kind == PoseSource::Kind::odom) resolveTopic(p.pose.name, p);  // a valid topic name
  resolveTopic(p.candidate_topic, p);
  calibration::Outside outside = calibration::kDefaultOutside;
  if (p.outside && !calibration::parseOutside(*p.outside, outside))
    throw InputError("", "-p outside:=" + *p.outside,
                     "is not a policy of `lidarcal correct --outside`",
                     std::string("see lidarcal correct --help; the default is ") +
                         calibration::toString(calibration::kDefaultOutside));
  if (p.candidate_file) {
    namespace fs = std::filesystem;
    const fs::path file = *p.candidate_file;
    const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
    std::error_code ec;
    if (file.empty() || !fs::is_directory(dir, ec) || fs::is_directory(file, ec))
      throw InputError("", "-p candidate_file:=" + file.string(),
                       "is not a file in an existing directory",
                       "give a path such as /tmp/candidate_model.json (the directory must exist)");
  }
}

}  // namespace

const char* toString(QosProfile q) {
  return q == QosProfile::sensor_data ? "sensor_data" : "default";
}

const char* toString(NodeMode m) {
  switch (m) {
    case NodeMode::apply:
      return "apply";
    case NodeMode::watch:
      return "watch";
    case NodeMode::learn:
      return "learn";
  }
  return "?";
}

NodeMode parseNodeMode(const std::string& text) {
  for (NodeMode m : {NodeMode::apply, NodeMode::watch, NodeMode::learn})
    if (text == toString(m)) return m;
  throw InputError("", "-p mode:=" + text, "is not a mode of this node",
                   "use apply (correct only), watch (correct and check the model) or learn "
                   "(also refit and switch)");
}

namespace {
constexpr RosDistro kDistros[] = {RosDistro::foxy,   RosDistro::galactic, RosDistro::humble,
                                  RosDistro::iron,   RosDistro::jazzy,    RosDistro::kilted,
                                  RosDistro::rolling};
}

const char* toString(RosDistro d) {
  switch (d) {
    case RosDistro::foxy:
      return "foxy";
    case RosDistro::galactic:
      return "galactic";
    case RosDistro::humble:
      return "humble";
    case RosDistro::iron:
      return "iron";
    case RosDistro::jazzy:
      return "jazzy";
    case RosDistro::kilted:
      return "kilted";
    case RosDistro::rolling:
      return "rolling";
  }
  return "?";
}

std::size_t gidBytes(RosDistro d) {
  return d == RosDistro::foxy || d == RosDistro::galactic || d == RosDistro::humble ? 24 : 16;
}

RosDistro parseRosDistro(const std::string& text) {
  std::string known;
  for (RosDistro d : kDistros) {
    if (text == toString(d)) return d;
    known += std::string(known.empty() ? "" : ", ") + toString(d);
  }
  throw InputError("", "-p ros_distro:=" + text, "is not a ROS 2 release this node knows",
                   "use one of " + known + " (the release of the other nodes)");
}

PoseSource parsePoseSource(const std::string& text) {
  const auto colon = text.find(':');
  const std::string kind = text.substr(0, colon);
  PoseSource s;
  s.name = colon == std::string::npos ? "" : text.substr(colon + 1);
  if ((kind != "odom" && kind != "tf") || s.name.empty() || s.name == "/")
    throw InputError("", "-p pose:=" + text,
                     "is odom:TOPIC (nav_msgs/msg/Odometry) or tf:FIXED_FRAME",
                     "e.g. -p pose:=odom:/odom or -p pose:=tf:map");
  s.kind = kind == "odom" ? PoseSource::Kind::odom : PoseSource::Kind::tf;
  if (s.kind == PoseSource::Kind::tf && s.name.front() == '/') s.name.erase(0, 1);
  return s;
}

NodeParameters parseNodeArguments(int argc, const char* const* argv) {
  NodeParameters p;
  bool ros_args = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&](const std::string& flag) -> std::string {
      if (i + 1 >= argc) throw InputError("", flag, "needs a value after it", kUsage);
      return argv[++i];
    };
    if (a == "--help" || a == "-h") {
      p.help = true;
    } else if (a == "--ros-args") {
      ros_args = true;
    } else if (a == "--") {
      ros_args = false;
    } else if (ros_args && (a == "-p" || a == "--param")) {
      const auto [name, value] = splitAssignment(next(a), a);
      setParameter(p, name, value);
    } else if (ros_args && (a == "-r" || a == "--remap")) {
      const auto [from, to] = splitAssignment(next(a), a);
      applyRemap(p, from, to);
    } else if (ros_args && (a == "--log-level" || a == "-e" || a == "--enclave")) {
      next(a);  // accepted as every ROS 2 node accepts them; logs go out at every level
    } else if (ros_args && a == "--params-file") {
      throw InputError("", a, "is not supported by this node (it is not an rclcpp node)",
                       "pass the parameters with -p NAME:=VALUE; a model exported as YAML goes in "
                       "-p model:=FILE.yaml");
    } else {
      throw InputError(
          "", a, ros_args ? "is not a ROS argument this node knows" : "is an unknown argument",
          kUsage);
    }
  }
  if (!p.help) checkParameters(p);
  return p;
}

std::string nodeHelp() {
  std::string h =
      "lidarcal_ros2_node: corrects a sensor_msgs/msg/LaserScan topic with a lidarcal model and "
      "republishes it\n"
      "(same header and intensities; ranges corrected with the rule of `lidarcal correct`).\n\n"
      "usage: lidarcal_ros2_node --ros-args [-p model:=MODEL] [-p NAME:=VALUE ...] [-r "
      "__node:=NAME] "
      "[-r __ns:=/NS] [-r FROM:=TO]\n\n"
      "parameters:\n"
      "  model        model.json of `lidarcal calibrate` (one sensor's or a rig's), or the YAML "
      "of\n"
      "               `lidarcal export --format yaml` (required, except in mode learn)\n"
      "  input        LaserScan topic to read (default scan)\n"
      "  output       topic of the corrected scans (default scan_corrected)\n"
      "  inversion    ls | ml, as `lidarcal correct --inversion` (default: the YAML's, else ls)\n"
      "  outside      readings outside the fitted range, as `lidarcal correct --outside` (default: "
      "the YAML's, else ";
  h += calibration::toString(calibration::kDefaultOutside);
  h += ")\n"
       "  sensor_name  the sensor's name as in the model; another name is refused at start "
       "(default: not checked).\n"
       "               With a rig model: the block to apply (name, topic or frame); unset: the "
       "block whose topic is input\n"
       "  force        true: apply a model whose range limits differ from the scans' (default "
       "false)\n"
       "  input_qos    sensor_data (best effort, keep last 5; default) or default (reliable, keep "
       "last 10)\n"
       "  output_qos   default (reliable, keep last 10; default) or sensor_data\n"
       "  ros_distro   the ROS 2 release of the other nodes: humble (default; also foxy, "
       "galactic) announces 24-byte\n"
       "               GIDs on ros_discovery_info, iron, jazzy, kilted, rolling 16-byte ones\n"
       "  pose         odom:TOPIC (nav_msgs/msg/Odometry, composed with the mount from "
       "/tf_static) or tf:FRAME\n"
       "               (the scan frame's pose in the fixed FRAME through /tf and /tf_static); "
       "default odom:odom.\n"
       "               Read in modes watch and learn (apply reads no poses)\n";
  h += watchHelp();
  h += "\n"
       "The node appears in `ros2 node list` as /NS/NAME, logs to /rosout as well as to stderr "
       "and states its\n"
       "model's health on /diagnostics (OK, WARN, ERROR; docs/ROS2.md).\n\n"
       "environment: ROS_DOMAIN_ID (default 0); CYCLONEDDS_URI configures the DDS participant "
       "(Cyclone DDS).\n"
       "exit status: 0 after Ctrl-C / SIGTERM, 2 a bad argument or a model of another sensor (at "
       "start or at the\n"
       "first scan), 3 a model that cannot correct. Malformed scans are dropped, counted and "
       "warned about.\n";
  return h;
}

std::string resolveTopic(const std::string& name, const NodeParameters& p) {
  const std::string fq = qualify(name, p);
  for (const auto& [from, to] : p.remaps)
    if (qualify(from, p) == fq) return qualify(to, p);
  return fq;
}

std::string fullyQualifiedNodeName(const NodeParameters& p) {
  return (p.node_namespace == "/" ? "" : p.node_namespace) + "/" + p.node_name;
}

std::string loggerName(const NodeParameters& p) {
  if (p.node_namespace == "/") return p.node_name;
  std::string name = p.node_namespace.substr(1);
  for (char& c : name)
    if (c == '/') c = '.';
  return name + "." + p.node_name;
}

std::string ddsTopicName(const std::string& resolved) { return "rt" + resolved; }

int domainIdFromEnvironment() {
  const char* text = std::getenv("ROS_DOMAIN_ID");
  if (!text || !*text) return 0;
  char* end = nullptr;
  const long id = std::strtol(text, &end, 10);
  if (*end != '\0' || id < 0 || id > 232)
    throw InputError("", std::string("ROS_DOMAIN_ID=") + text, "is not a domain id",
                     "use an integer from 0 to 232 (or unset it: 0)");
  return static_cast<int>(id);
}

}  // namespace lidarcal::ros2
