// SPDX-License-Identifier: BSD-3-Clause
// lidarcal_node: corrects a sensor_msgs/LaserScan topic live with a lidarcal model (ROS 1). In
// watch mode it also checks the model against the poles it passes, at a false-alarm rate the
// user sets, and reports on /diagnostics; in learn mode it also learns a new model after an alarm
// (or from the start, without ~model) and switches to it. Its parameters: ros/node_params.hpp
// (`--help` / `-h` prints them and exits 0 before contacting a master).
// Each scan is republished with the same header and beams; its ranges go through the rule of
// `lidarcal correct IN.bag` (ros/scan_path.hpp), so the node and a corrected bag agree bit for
// bit. A bad parameter or a model of another sensor (beam count, range limits, name) is refused
// with a ROS_FATAL line and the node exits with status 2 (3: the model itself cannot correct).

#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>

#include "common/errors.hpp"
#include "io/model_io.hpp"
#include "io/model_yaml.hpp"
#include "io/rig_model_io.hpp"
#include "pipeline/stages/stages.hpp"
#include "ros/node_params.hpp"
#include "ros/node_watch.hpp"
#include "ros/scan_path.hpp"

namespace {

using namespace lidarcal;
using namespace lidarcal::ros1;

/// The model of ~model (null without one: learn mode): a model.json (a rig model's block by
/// ~sensor_name or the input topic, named in `block`), or export's YAML (whose inversion and
/// outside policy apply unless ~inversion / ~outside are set).
std::shared_ptr<const CalibrationModel> loadModel(NodeSettings& s, std::string& block) {
  if (s.model_file.empty()) return nullptr;
  if (!io::isExportedModelYaml(s.model_file)) {
    CalibrationModel m =
        io::readModelForNode(s.model_file, s.sensor_name, ros::names::resolve(s.input), &block);
    // The block was chosen by this name: the block's own sensor_name need not repeat it.
    if (!block.empty()) s.sensor_name.reset();
    return std::make_shared<const CalibrationModel>(std::move(m));
  }
  io::ExportedModel e = io::readExportedModelYaml(s.model_file);
  if (!s.inversion) s.inversion = e.inversion;
  if (!s.outside) s.outside = e.outside;
  return std::make_shared<const CalibrationModel>(std::move(e.model));
}

class CorrectionNode {
 public:
  CorrectionNode(ros::NodeHandle& nh, const NodeSettings& s,
                 std::shared_ptr<const CalibrationModel> given, ScanPath& path,
                 calibration::Outside outside)
      : settings_(s),
        given_(std::move(given)),
        path_(path),
        outside_(outside),
        diagnostics_(nh, s.watch.diagnostics_period_s,
                     "lidarcal: range model of " + ros::names::resolve(s.input),
                     s.sensor_name.value_or(given_ ? given_->sensor_name : ""), path) {
    if (ros2::LivePoses* poses = path.poses()) {
      pose_input_ = std::make_unique<PoseInput>(nh, s.watch.pose, *poses);
      reporter_ = std::make_unique<WatchReporter>(nh, s.watch);
    }
    pub_ = nh.advertise<sensor_msgs::LaserScan>(s.output, 10);
    sub_ = nh.subscribe(s.input, 10, &CorrectionNode::onScan, this,
                        ros::TransportHints().tcpNoDelay());
  }
  int exitCode() const { return exit_code_; }

 private:
  /// The model given against the scan (beams; at the first scan range limits and name): false,
  /// with the node shutting down (exit status 2), when it is another sensor's.
  bool checkSensor(const sensor_msgs::LaserScan& msg) {
    try {
      pipeline::checkModelBeams(*given_, msg.ranges.size(), "topic " + sub_.getTopic(),
                                settings_.model_file);
      if (!checked_) {
        const pipeline::SensorFacts facts{
            settings_.sensor_name, io::float32Decimal(msg.range_min),
            io::float32Decimal(msg.range_max),
            "topic " + sub_.getTopic() + " (frame " + msg.header.frame_id + ")", "topic"};
        const std::string warning = pipeline::checkModelFitsSensor(
            *given_, facts, settings_.model_file, settings_.force, outside_);
        if (!warning.empty()) ROS_WARN("lidarcal_node: %s", warning.c_str());
        checked_ = true;
      }
      return true;
    } catch (const std::exception& e) {
      ROS_FATAL("lidarcal_node: refusing to correct %s with %s (a model of another sensor?): %s",
                sub_.getTopic().c_str(), settings_.model_file.c_str(), e.what());
      exit_code_ = 2;
      ros::shutdown();
      return false;
    }
  }

  void onScan(const sensor_msgs::LaserScan::ConstPtr& msg) {
    if (exit_code_ != 0) return;
    if (given_ && !checkSensor(*msg)) return;
    if (diagnostics_.hardwareId().empty()) diagnostics_.setHardwareId(msg->header.frame_id);
    // a deliberate copy: the received message is shared and const
    sensor_msgs::LaserScan out = *msg;
    const ScanOutcome outcome =
        path_.process(io::ros1ScanView(*msg), msg->header.frame_id, out.ranges);
    if (reporter_) reporter_->report(outcome, path_.stats());
    pub_.publish(out);
  }

  NodeSettings settings_;
  std::shared_ptr<const CalibrationModel> given_;  // the model of ~model (null: none given)
  ScanPath& path_;
  calibration::Outside outside_;
  DiagnosticsOutput diagnostics_;
  std::unique_ptr<PoseInput> pose_input_;    // watch and learn modes
  std::unique_ptr<WatchReporter> reporter_;  // watch and learn modes
  ros::Publisher pub_;
  ros::Subscriber sub_;
  bool checked_ = false;
  int exit_code_ = 0;
};

/// The ScanPath of the settings; a model the watcher cannot check is refused (InputError).
std::unique_ptr<ScanPath> makePath(const ScanPathSettings& p,
                                   std::shared_ptr<const CalibrationModel> model) {
  try {
    return std::make_unique<ScanPath>(p, std::move(model));
  } catch (const std::invalid_argument& e) {
    throw InputError(p.model_file, "~model", e.what(),
                     "watch and learn modes check the model.json of `lidarcal calibrate`, which "
                     "records the fit's covariance; or learn one with _mode:=learn and no ~model");
  }
}

void logStart(const NodeSettings& s, const CalibrationModel* model, const std::string& block) {
  std::string mode = toString(s.watch.mode);
  if (s.watch.mode != NodeMode::apply) {
    const watch::WatchSettings w = watchSettingsFrom(s.watch);
    char text[200];
    std::snprintf(text, sizeof text,
                  " (false alarms %.3g per %s, a check every %.3g m, poses %s:%s)",
                  w.false_alarms.per_unit, watch::toString(w.false_alarms.unit), w.check.every_m,
                  s.watch.pose.kind == ros2::PoseSource::Kind::odom ? "odom" : "tf",
                  s.watch.pose.name.c_str());
    mode += text;
  }
  const std::string in = ros::names::resolve(s.input), out = ros::names::resolve(s.output);
  const std::string block_text = block.empty() ? "" : " block " + block;
  if (!model) {
    ROS_INFO("lidarcal_node: passing %s -> %s uncorrected until a model is learnt; mode %s",
             in.c_str(), out.c_str(), mode.c_str());
    return;
  }
  const std::string fitted = model->fitted_range_m
                                 ? std::to_string(model->fitted_range_m->first) + "-" +
                                       std::to_string(model->fitted_range_m->second) + " m"
                                 : std::string("not recorded");
  ROS_INFO(
      "lidarcal_node: correcting %s -> %s with %s%s (sensor '%s', %s beams, fitted %s; inversion "
      "%s, outside %s); mode %s",
      in.c_str(), out.c_str(), s.model_file.c_str(), block_text.c_str(), model->sensor_name.c_str(),
      model->beams ? std::to_string(*model->beams).c_str() : "any", fitted.c_str(),
      s.inversion.value_or("ls").c_str(),
      s.outside.value_or(calibration::toString(calibration::kDefaultOutside)).c_str(),
      mode.c_str());
}

/// What the node did, on stdout (after ros::spin() the ROS logger may be shut down already).
void printSummary(const ScanPath& path) {
  const ScanPathStats& st = path.stats();
  const auto& c = st.correction;
  std::printf(
      "lidarcal_node: %zu scans, %zu returns corrected, %zu of them beyond the fitted range, %zu "
      "beyond it left uncorrected, %zu without a distance\n",
      c.scans, c.corrected + c.extrapolated, c.extrapolated, c.outside, c.unresolved);
  if (const watch::LiveWatcher* w = path.watcher()) {
    const watch::WatchState state = w->state();
    std::printf(
        "lidarcal_node: %zu scans watched (%zu without a pose, %zu while the watcher was behind), "
        "%.1f m: %zu tests, %zu alarms, %zu switches; %s: %s\n",
        state.scans, st.without_pose, w->dropped(), state.travel_m, state.checks, state.alarms,
        state.switches, watch::toString(state.level), state.message.c_str());
  }
  std::fflush(stdout);
}

int run(ros::NodeHandle& nh, NodeSettings& s) {
  std::string block;
  const std::shared_ptr<const CalibrationModel> model = loadModel(s, block);
  const std::string inversion = s.inversion.value_or("ls");
  if (inversion != "ls" && inversion != "ml") {  // a YAML's
    ROS_FATAL("lidarcal_node: the inversion is '%s': use ls or ml", inversion.c_str());
    return 2;
  }
  ScanPathSettings p;
  p.model_file = s.model_file;
  p.method =
      inversion == "ml" ? calibration::InversionMethod::ml : calibration::InversionMethod::ls;
  if (s.outside && !calibration::parseOutside(*s.outside, p.outside)) {  // a YAML's
    ROS_FATAL("lidarcal_node: the outside policy is '%s': use %s", s.outside->c_str(),
              calibration::outsideNames().c_str());
    return 2;
  }
  if (model) {
    pipeline::checkModelInvertible(*model, s.model_file, p.outside);
    // refused at start when the name is given; beams and limits at the first scan
    if (s.sensor_name)
      pipeline::checkModelFitsSensor(
          *model, {s.sensor_name, std::nullopt, std::nullopt, "~sensor_name", "node"}, s.model_file,
          s.force, p.outside);
  }
  if (s.watch.mode != NodeMode::apply) {
    p.watch = watchSettingsFrom(s.watch);
    p.poses.source = s.watch.pose;
  }
  if (s.watch.mode != NodeMode::learn && !s.watch.candidate_file.empty())
    ROS_WARN("lidarcal_node: ~candidate_file is written in learn mode only");
  const std::unique_ptr<ScanPath> path = makePath(p, model);
  CorrectionNode node(nh, s, model, *path, p.outside);
  logStart(s, model.get(), block);
  ros::spin();
  printSummary(*path);
  return node.exitCode();
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") {
      std::printf("%s", nodeHelp().c_str());  // before ros::init: no master is needed to read this
      return 0;
    }
  ros::init(argc, argv, "lidarcal_node");
  ros::NodeHandle nh, pnh("~");
  NodeSettings s;
  try {
    s = readNodeSettings(pnh);
  } catch (const InputError& e) {
    ROS_FATAL("lidarcal_node: %s", e.what());
    return 2;
  }
  try {
    return run(nh, s);
  } catch (const DataError& e) {
    ROS_FATAL("lidarcal_node: %s", e.what());
    return 3;
  } catch (const InputError& e) {
    ROS_FATAL("lidarcal_node: refusing the model: %s", e.what());
    return 2;
  } catch (const std::exception& e) {
    ROS_FATAL("lidarcal_node: %s", e.what());
    return 1;
  }
}
