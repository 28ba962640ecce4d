// SPDX-License-Identifier: BSD-3-Clause
// lidarcal calibrate RIG --out model.json: the joint calibration of a rig sequence's sensors.

#include <cstdio>

#include "calibration/rig_calibrate.hpp"
#include "common/errors.hpp"
#include "common/plural.hpp"
#include "detectors/rig_sightings.hpp"
#include "io/atomic_file.hpp"
#include "pipeline/commands/cmd_rig.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/rig_report.hpp"

namespace lidarcal::pipeline {
namespace {

calibration::RigConfig rigConfig(const RigCalibrateSettings& s, const io::Rig& rig) {
  calibration::RigConfig c;
  c.frame = s.frame == "vehicle"    ? calibration::RigFrame::vehicle
            : s.frame == "relative" ? calibration::RigFrame::relative
                                    : calibration::RigFrame::automatic;
  c.motion = s.options.motion_prior == "on"    ? calibration::MotionPrior::on
             : s.options.motion_prior == "off" ? calibration::MotionPrior::off
                                               : calibration::MotionPrior::automatic;
  if (!s.reference.empty()) {
    const auto k = rig.meta.find(s.reference);
    if (!k)
      throw InputError(rig.dir.string(), "--reference-sensor " + s.reference,
                       "names no sensor of the rig");
    c.reference = *k;
  }
  return c;
}

/// What to record when the data leave the mountings undetermined.
std::string whatToRecord(const io::Rig& rig) {
  if (!rig.meta.vehiclePosesKnown())
    return "record the vehicle's poses (import with --pose tf:FRAME or odom:TOPIC) while it drives "
           "through a turn "
           "past poles that two sensors see, or calibrate the mountings relative to one sensor "
           "(--rig-frame relative)";
  return "record poles that two sensors see at once, spread around the vehicle, while it turns by "
         "20 deg or more";
}

}  // namespace

void runRigCalibrate(const RigCalibrateSettings& s) {
  io::checkOutsideInput(s.dir, s.out);
  io::checkOutputFile(s.out, s.overwrite);
  const io::Rig rig = io::openRig(s.dir);
  detectors::RigDetectionSettings det;
  det.detection = detectionConfig(s.options).detection;
  if (!det.detection.landmark_radius_m)
    for (const auto& seq : rig.sequences)
      if (seq.meta.landmark_radius_m) det.detection.landmark_radius_m = seq.meta.landmark_radius_m;
  det.min_intensity = s.min_intensity;
  det.associate_m = s.associate_m;
  Activity detecting("detecting poles in " + plural(rig.scans.size(), "scan"));
  const detectors::RigCollected found = detectors::collectRigObservations(rig, det);
  detecting.finish();
  std::printf("| sensor | scans | circles | on poles | poles |\n|---|---|---|---|---|\n");
  for (std::size_t k = 0; k < found.sensors.size(); ++k) {
    const detectors::RigSensorDetections& d = found.sensors[k];
    std::printf("| %s | %zu | %zu | %zu | %zu |\n", rig.meta.sensors[k].name.c_str(), d.scans,
                d.detections, d.sightings, d.poles);
  }
  std::printf("%s, %zu seen by two sensors or more\n", plural(found.poles, "pole").c_str(),
              found.shared_poles);
  Activity fitting("fitting mountings, range models and poles jointly");
  const calibration::RigResult r = calibration::calibrateRig(found.observations, rigConfig(s, rig));
  fitting.finish();
  if (!r.ok())
    throw DataError(s.dir, "calibration", std::string(r.status.name()) + ": " + r.status.message,
                    whatToRecord(rig));
  const io::RigModel model = rigModel(rig, r);
  io::writeRigModel(s.out, model);
  std::fputs(rigMountingTable(model).c_str(), stdout);
  std::fputs(("\n" + rigSnippets(model)).c_str(), stdout);
  for (const std::string& note : model.notes) std::printf("  %s\n", note.c_str());
  for (const io::RigModelSensor& sensor : model.sensors)
    if (!sensor.model.status.ok())
      std::fprintf(stderr,
                   "lidarcal: warning: the range model of %s is not determined; correct refuses "
                   "its block "
                   "(the table's status says why)\n",
                   sensor.name.c_str());
  std::fprintf(stderr, "rig model (%s) written to %s\n",
               plural(model.sensors.size(), "sensor").c_str(), s.out.c_str());
}

}  // namespace lidarcal::pipeline
