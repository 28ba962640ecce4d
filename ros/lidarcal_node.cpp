// SPDX-License-Identifier: BSD-3-Clause
// lidarcal_node: corrects a sensor_msgs/LaserScan topic live with a lidarcal model (ROS 1).
//   ~model      model.json from `lidarcal calibrate` (of one sensor, or of a rig: see
//               ~sensor_name), or the YAML of `lidarcal export --format yaml` (required)
//   ~input      LaserScan topic to read (default "scan")
//   ~output     topic for the corrected scans (default "scan_corrected")
//   ~inversion  ls | ml, as `lidarcal correct --inversion` (default: the YAML's, else ls)
//   ~outside    as `lidarcal correct --outside` (default: the YAML's, else correct's default)
//   ~sensor_name  optional: the sensor's name as in model.json; another name is refused at start.
//               With a rig model it picks the sensor's block; unset, the block whose topic is
//               ~input (resolved)
//   ~force      apply a model whose range limits differ from the scans' (default false)
// `--help` / `-h` prints these and exits 0 before contacting a master.
// Each scan is republished with the same header and beams; its ranges go through the rule of
// `lidarcal correct IN.bag` (pipeline::correctLaserRanges), so the node and a corrected bag agree
// bit for bit. A model of another sensor (beam count, range limits, name) is refused with a
// ROS_FATAL line and the node exits with status 2 (3: the model itself cannot correct).

#include <cstdio>
#include <optional>
#include <string>

#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>

#include "common/errors.hpp"
#include "io/import.hpp"
#include "io/model_io.hpp"
#include "io/model_yaml.hpp"
#include "io/rig_model_io.hpp"
#include "pipeline/bag_correct.hpp"
#include "pipeline/stages.hpp"

namespace {

using namespace lidarcal;

struct NodeSettings {
  std::string model_file, input = "scan", output = "scan_corrected", inversion = "ls",
                          outside = calibration::toString(calibration::kDefaultOutside);
  std::optional<std::string> sensor_name;
  bool force = false;
  std::string block;  // the rig model's block applied ("" for a single-sensor model)
};

void printHelp() {
  std::printf(
      "lidarcal_node: corrects a sensor_msgs/LaserScan topic with a lidarcal model and republishes "
      "it (ROS 1)\n\n"
      "usage: lidarcal_node _model:=MODEL [_input:=scan] [_output:=scan_corrected] "
      "[_inversion:=ls|ml] [_outside:=POLICY]\n"
      "                     [_sensor_name:=NAME] [_force:=true] [__name:=NODE]\n\n"
      "private parameters:\n"
      "  ~model        model.json of `lidarcal calibrate` (one sensor's or a rig's), or the YAML "
      "of\n"
      "                `lidarcal export --format yaml` (required)\n"
      "  ~input        LaserScan topic to read (default scan)\n"
      "  ~output       topic of the corrected scans (default scan_corrected)\n"
      "  ~inversion    ls | ml, as `lidarcal correct --inversion` (default: the YAML's, else ls)\n"
      "  ~outside      readings outside the fitted range, as `lidarcal correct --outside` "
      "(default: the YAML's, else %s)\n"
      "  ~sensor_name  the sensor's name as in the model; another name is refused at start. With a "
      "rig model:\n"
      "                the block to apply (name, topic or frame); unset: the block whose topic is "
      "~input\n"
      "  ~force        true: apply a model whose range limits differ from the scans' (default "
      "false)\n\n"
      "exit status: 0 after Ctrl-C, 2 a bad parameter or a model of another sensor, 3 a model that "
      "cannot correct.\n",
      calibration::toString(calibration::kDefaultOutside));
}

/// The model of ~model: a model.json (a rig model's block by ~sensor_name or the input topic), or
/// export's YAML (whose inversion and outside policy apply unless ~inversion / ~outside are set).
CalibrationModel loadModel(NodeSettings& s, bool inversion_set, bool outside_set) {
  if (!io::isExportedModelYaml(s.model_file)) {
    CalibrationModel m =
        io::readModelForNode(s.model_file, s.sensor_name, ros::names::resolve(s.input), &s.block);
    // The block was chosen by this name: the block's own sensor_name need not repeat it.
    if (!s.block.empty()) s.sensor_name.reset();
    return m;
  }
  io::ExportedModel e = io::readExportedModelYaml(s.model_file);
  if (!inversion_set) s.inversion = e.inversion;
  if (!outside_set) s.outside = e.outside;
  return std::move(e.model);
}

class CorrectionNode {
 public:
  CorrectionNode(ros::NodeHandle& nh, const NodeSettings& s, const CalibrationModel& model,
                 const calibration::ReadingCorrector& correct, calibration::Outside outside)
      // correct_: a MemoCorrector
      : settings_(s), model_(model), correct_(correct), outside_(outside) {
    pub_ = nh.advertise<sensor_msgs::LaserScan>(s.output, 10);
    sub_ = nh.subscribe(s.input, 10, &CorrectionNode::onScan, this,
                        ros::TransportHints().tcpNoDelay());
  }
  int exitCode() const { return exit_code_; }
  const pipeline::CorrectionStats& stats() const { return stats_; }

 private:
  void onScan(const sensor_msgs::LaserScan::ConstPtr& msg) {
    if (exit_code_ != 0) return;
    const double range_min = io::float32Decimal(msg->range_min),
                 range_max = io::float32Decimal(msg->range_max);
    try {
      pipeline::checkModelBeams(model_, msg->ranges.size(), "topic " + sub_.getTopic(),
                                settings_.model_file);
      if (!checked_) {
        const pipeline::SensorFacts facts{
            settings_.sensor_name, range_min, range_max,
            "topic " + sub_.getTopic() + " (frame " + msg->header.frame_id + ")", "topic"};
        const std::string warning = pipeline::checkModelFitsSensor(
            model_, facts, settings_.model_file, settings_.force, outside_);
        if (!warning.empty()) ROS_WARN("lidarcal_node: %s", warning.c_str());
        checked_ = true;
      }
    } catch (const std::exception& e) {
      ROS_FATAL("lidarcal_node: refusing to correct %s with %s (a model of another sensor?): %s",
                sub_.getTopic().c_str(), settings_.model_file.c_str(), e.what());
      exit_code_ = 2;
      ros::shutdown();
      return;
    }
    // a deliberate copy: the received message is shared and const
    sensor_msgs::LaserScan out = *msg;
    pipeline::correctLaserRanges(out.ranges, range_min, range_max, correct_, stats_);
    ++stats_.scans;
    pub_.publish(out);
  }

  NodeSettings settings_;
  CalibrationModel model_;
  // remembers the readings seen: a lookup per beam after the first scans
  pipeline::MemoCorrector correct_;
  calibration::Outside outside_;
  ros::Publisher pub_;
  ros::Subscriber sub_;
  pipeline::CorrectionStats stats_;
  bool checked_ = false;
  int exit_code_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") {
      printHelp();  // before ros::init: no master is needed to read this
      return 0;
    }
  ros::init(argc, argv, "lidarcal_node");
  ros::NodeHandle nh, pnh("~");
  NodeSettings s;
  if (!pnh.getParam("model", s.model_file) || s.model_file.empty()) {
    ROS_FATAL(
        "lidarcal_node: parameter ~model is not set: give this sensor's model.json (e.g. "
        "_model:=/path/model.json)");
    return 2;
  }
  pnh.param("input", s.input, s.input);
  pnh.param("output", s.output, s.output);
  const bool inversion_set = pnh.getParam("inversion", s.inversion);
  const bool outside_set = pnh.getParam("outside", s.outside);
  pnh.param("force", s.force, s.force);
  if (std::string name; pnh.getParam("sensor_name", name)) s.sensor_name = name;
  calibration::Outside outside = calibration::kDefaultOutside;
  try {
    const CalibrationModel model = loadModel(s, inversion_set, outside_set);
    if (s.inversion != "ls" && s.inversion != "ml") {
      ROS_FATAL("lidarcal_node: ~inversion is '%s': use ls or ml", s.inversion.c_str());
      return 2;
    }
    if (!calibration::parseOutside(s.outside, outside)) {
      ROS_FATAL("lidarcal_node: ~outside is '%s': use %s", s.outside.c_str(),
                calibration::outsideNames().c_str());
      return 2;
    }
    const auto method =
        s.inversion == "ml" ? calibration::InversionMethod::ml : calibration::InversionMethod::ls;
    pipeline::checkModelInvertible(model, s.model_file, outside);
    // refused at start when the name is given; beams and limits at the first scan
    if (s.sensor_name)
      pipeline::checkModelFitsSensor(
          model, {s.sensor_name, std::nullopt, std::nullopt, "~sensor_name", "node"}, s.model_file,
          s.force, outside);
    const calibration::ReadingCorrector correct =
        pipeline::modelCorrector(model, method, outside, s.model_file);
    CorrectionNode node(nh, s, model, correct, outside);
    const std::string fitted = model.fitted_range_m
                                   ? std::to_string(model.fitted_range_m->first) + "-" +
                                         std::to_string(model.fitted_range_m->second) + " m"
                                   : std::string("not recorded");
    const std::string block = s.block.empty() ? "" : " block " + s.block;
    ROS_INFO(
        "lidarcal_node: correcting %s -> %s with %s%s (sensor '%s', %s beams, fitted %s; inversion "
        "%s, outside %s)",
        ros::names::resolve(s.input).c_str(), ros::names::resolve(s.output).c_str(),
        s.model_file.c_str(), block.c_str(), model.sensor_name.c_str(),
        model.beams ? std::to_string(*model.beams).c_str() : "any", fitted.c_str(),
        s.inversion.c_str(), s.outside.c_str());
    ros::spin();
    const auto& st = node.stats();
    // After ros::spin() the ROS logger may be shut down already: plain stdout.
    std::printf(
        "lidarcal_node: %zu scans, %zu returns corrected, %zu of them beyond the fitted range, %zu "
        "beyond it left "
        "uncorrected, %zu without a distance\n",
        st.scans, st.corrected + st.extrapolated, st.extrapolated, st.outside, st.unresolved);
    std::fflush(stdout);
    return node.exitCode();
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
