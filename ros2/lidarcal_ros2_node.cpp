// SPDX-License-Identifier: BSD-3-Clause
// lidarcal_ros2_node: corrects a sensor_msgs/msg/LaserScan topic live with a lidarcal model, as
// a ROS 2 node seen by `ros2 node list`, `ros2 topic list`, `ros2 topic info -v` and `ros2 topic
// echo`: a DDS participant (Cyclone DDS) that follows ROS 2's conventions (topic "rt/<name>",
// type sensor_msgs::msg::dds_::LaserScan_, plain CDR, ROS 2's QoS profiles, ROS_DOMAIN_ID) and
// announces itself on ros_discovery_info. Parameters: ros2/node_args.hpp (--help).
//
// Each scan is corrected with the rule of `lidarcal correct` (ros2::LiveCorrector) and republished
// with the same header, angles and intensities; in modes watch and learn the field watcher checks
// the model beside it and, in learn mode, switches to a new one (ros2/node_watch.hpp). The
// model's health goes to /diagnostics in every mode. A model of another sensor is refused at the
// first scan (exit 2); malformed scans are dropped with a rate-limited warning and counted.
// SIGINT/SIGTERM end it with a summary line and exit status 0. The start line, the warnings, a
// refusal and the summary go to /rosout as well as to stderr (the summary: stdout).

#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>

#include "common/errors.hpp"
#include "io/model_io.hpp"
#include "io/model_yaml.hpp"
#include "io/rig_model_io.hpp"
#include "ros2/cyclone_relay.hpp"
#include "ros2/live_corrector.hpp"
#include "ros2/node_args.hpp"
#include "ros2/node_outputs.hpp"
#include "ros2/node_watch.hpp"
#include "ros2/ros_participant.hpp"
#include "ros2/warning_limiter.hpp"

namespace {

using namespace lidarcal;

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

/// The model and how to correct with it: the node's parameters first, then what an exported
/// YAML says, then the defaults of `correct`.
struct LoadedModel {
  std::shared_ptr<const CalibrationModel> model;  ///< null: mode learn without a model
  std::string block;  ///< the rig model's block applied ("" for a single-sensor model)
  std::string inversion = "ls";
  calibration::Outside outside = calibration::kDefaultOutside;
};

LoadedModel loadModel(const ros2::NodeParameters& p) {
  LoadedModel m;
  if (p.model_file.empty()) {  // mode learn: nothing to read
  } else if (io::isExportedModelYaml(p.model_file)) {
    io::ExportedModel e = io::readExportedModelYaml(p.model_file);
    m.model = std::make_shared<const CalibrationModel>(std::move(e.model));
    m.inversion = e.inversion;
    if (!calibration::parseOutside(e.outside, m.outside))
      throw InputError(p.model_file, "outside",
                       "'" + e.outside + "' is not a policy of `lidarcal correct --outside`",
                       "export the model again, or set -p outside:=...");
  } else {
    m.model = std::make_shared<const CalibrationModel>(io::readModelForNode(
        p.model_file, p.sensor_name, ros2::resolveTopic(p.input, p), &m.block));
  }
  if (p.inversion) m.inversion = *p.inversion;
  if (p.outside) calibration::parseOutside(*p.outside, m.outside);  // checked by parseNodeArguments
  if (m.inversion != "ls" && m.inversion != "ml")
    throw InputError(p.model_file, "inversion", "'" + m.inversion + "' is not ls or ml",
                     "set -p inversion:=ls");
  return m;
}

/// A log line to stderr (or `stream`) and to /rosout.
struct NodeLog {
  ros2::RosoutLogger& rosout;
  void line(ros2::LogLevel level, const std::string& text, const ros2::LogOrigin& origin,
            std::FILE* stream = stderr) {
    const char* tag = level == ros2::LogLevel::warn    ? "warning: "
                      : level >= ros2::LogLevel::error ? "error: "
                                                       : "";
    std::fprintf(stream, "lidarcal_ros2_node: %s%s\n", tag, text.c_str());
    std::fflush(stream);
    rosout.log({ros2::wallClockNow(), level, text, origin});
  }
};

double nowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string summary(const ros2::LiveStats& st) {
  const auto& c = st.correction;
  char text[256];
  std::snprintf(text, sizeof text,
                "%zu scans, %zu returns corrected, %zu outside the fitted readings, %zu without a "
                "distance; %zu malformed scans dropped",
                c.scans, c.corrected, c.outside, c.unresolved, st.droppedTotal());
  std::string out = text;
  for (std::size_t r = 0; r < st.dropped.size(); ++r)
    if (st.dropped[r] > 0)
      out += ", " + std::to_string(st.dropped[r]) + " " +
             ros2::toString(static_cast<ros2::DropReason>(r));
  if (st.uncorrected > 0) out += "; " + std::to_string(st.uncorrected) + " passed uncorrected";
  return out;
}

/// The start line: topics, domain, mode, model and how it corrects.
std::string startLine(const ros2::NodeParameters& p, const LoadedModel& m,
                      const ros2::LiveSettings& s, const std::string& output, int domain) {
  std::string with = "no model yet (learning one; scans pass uncorrected until then)";
  if (m.model) {
    const std::string block = m.block.empty() ? "" : " block " + m.block;
    const std::string beams = m.model->beams ? std::to_string(*m.model->beams) : "any";
    with = p.model_file + block + " (sensor '" + m.model->sensor_name + "', " + beams +
           " beams; inversion " + m.inversion + ", outside " + calibration::toString(s.outside) +
           ")";
  }
  return "correcting " + s.topic + " -> " + output + " on domain " + std::to_string(domain) +
         " with " + with + ", mode " + ros2::toString(p.mode) + "; node " +
         ros2::fullyQualifiedNodeName(p) + " (ros_distro " + ros2::toString(p.ros_distro) + ")";
}

/// How the node corrects, from its parameters and the model; a model given is checked here.
ros2::LiveSettings liveSettings(const ros2::NodeParameters& p, const LoadedModel& m) {
  ros2::LiveSettings s;
  s.model_file = p.model_file;
  s.topic = ros2::resolveTopic(p.input, p);
  s.method =
      m.inversion == "ml" ? calibration::InversionMethod::ml : calibration::InversionMethod::ls;
  s.outside = m.outside;
  // A rig model's block chosen by sensor_name: the block's own sensor_name need not repeat it.
  if (m.block.empty()) s.sensor_name = p.sensor_name;
  s.force = p.force;
  if (!m.model) return s;
  pipeline::checkModelInvertible(*m.model, p.model_file, s.outside);
  if (s.sensor_name)  // refused at start when the name is given; beams and limits at the first scan
    pipeline::checkModelFitsSensor(
        *m.model, {s.sensor_name, std::nullopt, std::nullopt, "parameter sensor_name", "node"},
        p.model_file, p.force, s.outside);
  return s;
}

int run(const ros2::NodeParameters& p) {
  const LoadedModel m = loadModel(p);
  const ros2::LiveSettings s = liveSettings(p, m);
  ros2::ParticipantSettings ps;
  ps.domain_id = ros2::domainIdFromEnvironment();
  ps.node_name = p.node_name;
  ps.node_namespace = p.node_namespace;
  ps.ros_distro = p.ros_distro;
  ros2::RosParticipant participant(ps);
  ros2::RosoutLogger rosout(participant, ros2::loggerName(p));
  NodeLog log{rosout};
  ros2::NodeScanPath path(participant, p, {m.model, s},
                          [&log](ros2::LogLevel level, const std::string& text,
                                 const ros2::LogOrigin& origin) { log.line(level, text, origin); });
  ros2::RelayConfig rc;
  rc.input_topic = ros2::ddsTopicName(s.topic);
  const std::string output = ros2::resolveTopic(p.output, p);
  rc.output_topic = ros2::ddsTopicName(output);
  rc.input_qos = p.input_qos;
  rc.output_qos = p.output_qos;
  ros2::CycloneRelay relay(participant, rc);
  log.line(ros2::LogLevel::info, startLine(p, m, s, output, ps.domain_id), LIDARCAL_LOG_ORIGIN);

  ros2::WarningLimiter warnings;
  int status = 0;
  while (!g_stop && status == 0) {
    relay.spinOnce(0.2, [&](sensor_msgs_msg_dds__LaserScan_& scan) {
      if (status != 0) return false;
      const ros2::ScanVerdict v = path.process(scan, nowSeconds());
      const ros2::LiveCorrector& corrector = path.corrector();
      if (v == ros2::ScanVerdict::refuse) {
        log.line(ros2::LogLevel::error,
                 "refusing to correct " + s.topic + " with " + p.model_file +
                     " (a model of another sensor?): " + corrector.message(),
                 LIDARCAL_LOG_ORIGIN);
        status = 2;
        return false;
      }
      if (v == ros2::ScanVerdict::drop) {
        const std::string w = warnings.offer(ros2::toString(corrector.dropReason()),
                                             "dropped " + corrector.message(), nowSeconds());
        if (!w.empty()) log.line(ros2::LogLevel::warn, w, LIDARCAL_LOG_ORIGIN);
        return false;
      }
      if (!corrector.sensorWarning().empty() && corrector.stats().correction.scans == 1)
        log.line(ros2::LogLevel::warn, corrector.sensorWarning(), LIDARCAL_LOG_ORIGIN);
      return true;
    });
    path.tick(nowSeconds());
  }
  log.line(ros2::LogLevel::info, summary(path.corrector().stats()) + path.watchSummary(),
           LIDARCAL_LOG_ORIGIN, stdout);
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  try {
    const ros2::NodeParameters p = ros2::parseNodeArguments(argc, argv);
    if (p.help) {
      std::fputs(ros2::nodeHelp().c_str(), stdout);
      return 0;
    }
    return run(p);
  } catch (const DataError& e) {
    std::fprintf(stderr, "lidarcal_ros2_node: %s\n", e.what());
    return 3;
  } catch (const InputError& e) {
    std::fprintf(stderr, "lidarcal_ros2_node: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lidarcal_ros2_node: %s\n", e.what());
    return 1;
  }
}
