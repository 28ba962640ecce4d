// SPDX-License-Identifier: BSD-3-Clause
#include "ros/node_params.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include <ros/node_handle.h>

#include "calibration/filtering.hpp"
#include "common/errors.hpp"

namespace lidarcal::ros1 {
namespace {

namespace fs = std::filesystem;

/// Reads ~name into `value` when it is set; throws InputError when it is set to a value of
/// another type (`kind` says which type is wanted, `example` a value that would do).
template <class T>
bool readParam(const ros::NodeHandle& pnh, const std::string& name, T& value, const char* kind,
               const std::string& example) {
  if (!pnh.hasParam(name)) return false;
  if (!pnh.getParam(name, value))
    throw InputError("", "~" + name, std::string("is not ") + kind,
                     "e.g. _" + name + ":=" + example);
  return true;
}

/// Reads ~name, a number above 0 (`what` names it for the message), into `value` when set.
bool readPositive(const ros::NodeHandle& pnh, const std::string& name, double& value,
                  const std::string& what, const std::string& example) {
  if (!readParam(pnh, name, value, "a number", example)) return false;
  if (!(value > 0.0) || !std::isfinite(value)) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", value);
    throw InputError("", "~" + name, std::string("is ") + text + ": " + what + " must be above 0",
                     "e.g. _" + name + ":=" + example);
  }
  return true;
}

/// ~name, one of `choices` (a value of the list `names`, e.g. "apply, watch or learn").
template <class E>
bool readChoice(const ros::NodeHandle& pnh, const std::string& name,
                std::initializer_list<std::pair<const char*, E>> choices, const std::string& names,
                E& value) {
  std::string text;
  if (!readParam(pnh, name, text, "a string", choices.begin()->first)) return false;
  for (const auto& [key, v] : choices)
    if (text == key) return value = v, true;
  throw InputError("", "~" + name, "'" + text + "' is not " + names,
                   std::string("e.g. _") + name + ":=" + choices.begin()->first);
}

/// Refuses a candidate file that could not be written: its directory missing, or a directory.
void checkCandidateFile(const std::string& file) {
  const fs::path f(file);
  const fs::path dir = f.has_parent_path() ? f.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(file, "~candidate_file", "its directory " + dir.string() + " does not exist",
                     "create it, or give another path");
  if (fs::is_directory(f, ec))
    throw InputError(file, "~candidate_file", "is a directory",
                     "give a file name, e.g. _candidate_file:=/tmp/candidate_model.json");
}

WatchParameters readWatchParameters(const ros::NodeHandle& pnh) {
  WatchParameters w;
  readChoice(pnh, "mode",
             {{"apply", NodeMode::apply}, {"watch", NodeMode::watch}, {"learn", NodeMode::learn}},
             "apply, watch or learn", w.mode);
  readPositive(pnh, "false_alarms", w.false_alarms, "the expected false alarms per km or hour",
               "0.1");
  readChoice(pnh, "false_alarms_per",
             {{"km", watch::Exposure::distance}, {"hour", watch::Exposure::time}}, "km or hour",
             w.false_alarms_per);
  readPositive(pnh, "check_every", w.check_every_m, "the metres between checks", "3");
  if (readParam(pnh, "check_bias_replicas", w.check_bias_replicas, "a whole number", "4") &&
      (w.check_bias_replicas < 0 || w.check_bias_replicas > 100))
    throw InputError("", "~check_bias_replicas",
                     "is " + std::to_string(w.check_bias_replicas) + ": must be in 0..100",
                     "e.g. _check_bias_replicas:=4");
  double radius = 0.0;
  if (readPositive(pnh, "landmark_radius", radius, "the poles' radius in metres", "0.05"))
    w.landmark_radius_m = radius;
  if (std::string text; readParam(pnh, "pose", text, "a string", "odom:/odom")) try {
      w.pose = ros2::parsePoseSource(text);
    } catch (const InputError&) {
      throw InputError("", "~pose", "'" + text + "' is not odom:TOPIC or tf:FIXED_FRAME",
                       "e.g. _pose:=odom:/odom (nav_msgs/Odometry) or _pose:=tf:map");
    }
  if (readParam(pnh, "candidate_topic", w.candidate_topic, "a string", "~candidate_model") &&
      w.candidate_topic.empty())
    throw InputError("", "~candidate_topic", "is empty", "e.g. _candidate_topic:=~candidate_model");
  if (readParam(pnh, "candidate_file", w.candidate_file, "a string", "/tmp/candidate_model.json") &&
      !w.candidate_file.empty())
    checkCandidateFile(w.candidate_file);
  readPositive(pnh, "diagnostics_period", w.diagnostics_period_s,
               "the seconds between two /diagnostics messages", "1");
  return w;
}

}  // namespace

NodeSettings readNodeSettings(const ros::NodeHandle& pnh) {
  NodeSettings s;
  readParam(pnh, "model", s.model_file, "a file name", "/path/model.json");
  readParam(pnh, "input", s.input, "a topic name", "/scan");
  readParam(pnh, "output", s.output, "a topic name", "/scan_corrected");
  if (std::string text; readParam(pnh, "inversion", text, "a string", "ls")) {
    if (text != "ls" && text != "ml")
      throw InputError("", "~inversion", "'" + text + "' is not ls or ml", "e.g. _inversion:=ls");
    s.inversion = text;
  }
  if (std::string text; readParam(pnh, "outside", text, "a string", "linear")) {
    calibration::Outside unused;
    if (!calibration::parseOutside(text, unused))
      throw InputError("", "~outside", "'" + text + "' is not a policy",
                       "use " + calibration::outsideNames());
    s.outside = text;
  }
  if (std::string text; readParam(pnh, "sensor_name", text, "a string", "front"))
    s.sensor_name = text;
  readParam(pnh, "force", s.force, "true or false", "true");
  s.watch = readWatchParameters(pnh);
  if (s.model_file.empty() && s.watch.mode != NodeMode::learn)
    throw InputError("", "~model", "is not set",
                     "give this sensor's model.json (e.g. _model:=/path/model.json), or learn one "
                     "with _mode:=learn");
  return s;
}

watch::WatchSettings watchSettingsFrom(const WatchParameters& p) {
  watch::WatchSettings s = watch::defaultWatchSettings();
  s.mode = p.mode == NodeMode::learn ? watch::Mode::learn : watch::Mode::watch;
  s.false_alarms.per_unit = p.false_alarms;
  s.false_alarms.unit = p.false_alarms_per;
  s.check.every_m = p.check_every_m;
  s.check.bias_replicas = p.check_bias_replicas;
  s.check.landmark_radius_m = p.landmark_radius_m;
  s.detection.landmark_radius_m = p.landmark_radius_m;
  return s;
}

std::string nodeHelp() {
  return "lidarcal_node: corrects a sensor_msgs/LaserScan topic with a lidarcal model and "
         "republishes it (ROS 1);\n"
         "in watch and learn modes it also checks the model against the poles it passes\n\n"
         "usage: lidarcal_node _model:=MODEL [_input:=scan] [_output:=scan_corrected] "
         "[_mode:=apply|watch|learn] [_NAME:=VALUE ...] [__name:=NODE]\n\n"
         "private parameters:\n"
         "  ~model        model.json of `lidarcal calibrate` (one sensor's or a rig's), or the "
         "YAML "
         "of\n"
         "                `lidarcal export --format yaml` (required, but in learn mode)\n"
         "  ~input        LaserScan topic to read (default scan)\n"
         "  ~output       topic of the corrected scans (default scan_corrected)\n"
         "  ~inversion    ls | ml, as `lidarcal correct --inversion` (default: the YAML's, else "
         "ls)\n"
         "  ~outside      readings outside the fitted range, as `lidarcal correct --outside` "
         "(default: the YAML's, else " +
         std::string(calibration::toString(calibration::kDefaultOutside)) +
         ")\n"
         "  ~sensor_name  the sensor's name as in the model; another name is refused at start. "
         "With a rig model:\n"
         "                the block to apply (name, topic or frame); unset: the block whose topic "
         "is ~input\n"
         "  ~force        true: apply a model whose range limits differ from the scans' (default "
         "false)\n"
         "  ~mode         apply (default: correct only) | watch (also check the model against "
         "the poles passed,\n"
         "                at a set false-alarm rate) | learn (also refit after an alarm and "
         "switch to the new model)\n"
         "watch and learn modes:\n"
         "  ~false_alarms      expected false alarms per unit while the model holds (default "
         "0.1)\n"
         "  ~false_alarms_per  km (default) | hour (of driving)\n"
         "  ~check_every       metres of travel between two checks (default 3)\n"
         "  ~check_bias_replicas  replicas that estimate a check fit's own bias, for the checks "
         "tested against zero\n"
         "                (0: none; default " +
         std::to_string(watch::CheckSettings{}.bias_replicas) +
         ")\n"
         "  ~landmark_radius   the poles' radius, metres (default: estimated)\n"
         "  ~pose              odom:TOPIC (nav_msgs/Odometry, default odom:/odom) | "
         "tf:FIXED_FRAME (/tf, /tf_static)\n"
         "  ~candidate_topic   learn mode: each refit's model as JSON, std_msgs/String, latched "
         "(default ~candidate_model)\n"
         "  ~candidate_file    learn mode: each refit's model also written to this file "
         "(default: none)\n"
         "  ~diagnostics_period  seconds between two /diagnostics messages (default 1)\n\n"
         "exit status: 0 after Ctrl-C, 2 a bad parameter or a model of another sensor, 3 a model "
         "that cannot correct.\n";
}

}  // namespace lidarcal::ros1
