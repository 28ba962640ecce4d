#include "pipeline/reference_stage.hpp"

#include <set>

#include "calibration/filtering.hpp"
#include "common/errors.hpp"
#include "detectors/walls.hpp"
#include "pipeline/collect_sightings.hpp"

namespace lidarcal::pipeline {

detectors::ScanLoader scanLoader(const io::Sequence& seq, const ScanCorrection* correct) {
  return [&seq, correct](std::size_t i) {
    io::Scan scan = io::readScan(seq.scans.path(i));
    return correct ? calibration::correctScan(scan, correct->inverter, nullptr, correct->window) : scan;
  };
}

detectors::SequenceDetectionConfig referenceDetection(detectors::SequenceDetectionConfig detection) {
  detection.association.min_stops = 1;
  // Close to the sensor a pole fills a wide arc that the sensor reads unevenly (time-of-flight
  // near field): it may be found in fewer than half of the scans.
  detection.association.min_scan_fraction = 0.25;
  return detection;
}

namespace {

/// Walls of every scan at the stops that a reference measures a wall at.
std::vector<WallSighting> observeWalls(const io::Sequence& seq, const Reference& ref, const detectors::ScanLoader& load) {
  std::set<std::size_t> stops;
  for (const auto& d : ref.distances)
    if (d.target == ReferenceTarget::wall) stops.insert(d.stop);
  std::vector<WallSighting> walls;
  const detectors::WallConfig config;
  for (std::size_t k : stops) {
    for (std::size_t i : seq.stops[k].scans) {
      const io::Scan scan = load(i);
      for (const detectors::Wall& w : detectors::findWalls(*scan.cloud, config)) {
        WallSighting ws;
        ws.stop = k;
        ws.scan = i;
        ws.normal_rad = w.normal_rad;
        ws.distance_m = w.distance_m;
        for (const auto idx : w.inliers) {
          const auto& p = (*scan.cloud)[static_cast<std::size_t>(idx)];
          ws.beams.push_back(BeamReading{std::atan2(static_cast<double>(p.y), static_cast<double>(p.x)),
                                         std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)),
                                         static_cast<std::uint32_t>(idx)});
        }
        walls.push_back(std::move(ws));
      }
    }
  }
  return walls;
}

}  // namespace

ReferenceObservations observeReference(const io::Sequence& seq, const Reference& ref,
                                       const detectors::SequenceDetectionConfig& detection,
                                       const detectors::ScanLoader& load, const StageProgress& on_scan) {
  ReferenceObservations out;
  bool poles = false;
  for (const auto& d : ref.distances) poles = poles || d.target == ReferenceTarget::landmark;
  if (poles) {
    const detectors::SequenceDetections det = detectors::detectSequence(seq, load, detection, on_scan);
    out.observations = toLandmarkObservations(seq, det, load);
    out.landmarks = det.association.landmarks.size();
  } else {
    for (const auto& stop : seq.stops) out.observations.commanded.push_back(stop.commanded);
    out.observations.range_min_m = seq.meta.range_min_m.value_or(0.0);
    out.observations.range_max_m = seq.meta.range_max_m.value_or(1e9);
  }
  out.observations.walls = observeWalls(seq, ref, load);
  const double radius = detection.detection.landmark_radius_m.value_or(seq.meta.landmark_radius_m.value_or(0.0));
  out.known = calibration::knownReadings(out.observations, ref, radius);
  return out;
}

SequenceCalibration calibrateSequenceWithReference(const io::Sequence& seq, const Reference& ref,
                                           const std::filesystem::path& ref_file,
                                           const detectors::SequenceDetectionConfig& detection,
                                           const calibration::CalibrationConfig& config,
                                           std::vector<calibration::ReferenceMatch>* matches,
                                           const StageProgress& on_scan) {
  if (ref.distances.empty())
    throw InputError(ref_file.string(), "distances",
                     "is empty: calibrating against a reference needs measured distances at 3 or more stops",
                     "add the distances you measured (docs/FORMAT.md, \"Reference measurements\")");
  ReferenceObservations ro = observeReference(seq, ref, referenceDetection(detection), scanLoader(seq), on_scan);
  if (matches) *matches = ro.known.matches;
  std::string unmatched;
  std::size_t failures = 0;
  for (const auto& m : ro.known.matches)
    if (!m.ok()) {
      if (failures++ < 5) unmatched += (unmatched.empty() ? "" : "; ") + std::string("distances[") + std::to_string(m.entry) + "]: " + m.status;
    }
  if (failures > 5) unmatched += "; and " + std::to_string(failures - 5) + " more";
  if (failures > 0)
    throw DataError(ref_file.string(), "distances", unmatched,
                    "check the stop numbers (lidarcal info), give bearing_rad to pick the target, or remove the entry");
  SequenceCalibration out;
  out.observations = std::move(ro.observations);
  out.model = calibration::calibrateWithReference(ro.known.readings, config, out.observations.range_min_m,
                                                  out.observations.range_max_m);
  if (seq.meta.sensor_name) out.model.sensor_name = *seq.meta.sensor_name;
  const auto [fewest, most] = io::pointCountRange(seq);
  if (seq.meta.beams) out.model.beams = seq.meta.beams;
  else if (fewest == most && most > 0) out.model.beams = static_cast<int>(most);
  out.detections.association.assigned = ro.known.readings.size();
  return out;
}

}  // namespace lidarcal::pipeline
