// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/reference_stage.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <set>

#include "calibration/filtering.hpp"
#include "calibration/held_out.hpp"
#include "common/errors.hpp"
#include "detectors/sightings.hpp"
#include "detectors/stop_walls.hpp"

namespace lidarcal::pipeline {

detectors::ScanLoader scanLoader(const io::Sequence& seq,
                                 const calibration::ReadingCorrector* correct) {
  return [&seq, correct](std::size_t i) {
    io::Scan scan = io::readScan(seq.scans.path(i));
    return correct ? calibration::correctScan(scan, *correct) : scan;
  };
}

detectors::SequenceDetectionConfig referenceDetection(
    detectors::SequenceDetectionConfig detection) {
  detection.association.min_stops = 1;
  // Close to the sensor a pole fills a wide arc that the sensor reads unevenly (time-of-flight
  // near field): it may be found in fewer than half of the scans.
  detection.association.min_scan_fraction = 0.25;
  return detection;
}

namespace {

/// The stops a reference measures a wall or a span at.
std::set<std::size_t> wallStops(const Reference& ref) {
  std::set<std::size_t> stops;
  for (const auto& d : ref.distances)
    if (d.target == ReferenceTarget::wall) stops.insert(d.stop);
  for (const auto& s : ref.spans) stops.insert(s.stop);
  return stops;
}

}  // namespace

ReferenceObservations observeReference(const io::Sequence& seq, const Reference& ref,
                                       const detectors::SequenceDetectionConfig& detection,
                                       const detectors::ScanLoader& load,
                                       const StageProgress& on_scan) {
  ReferenceObservations out;
  bool poles = false;
  for (const auto& d : ref.distances) poles = poles || d.target == ReferenceTarget::landmark;
  if (poles) {
    const detectors::SequenceDetections det =
        detectors::detectSequence(seq, load, detection, on_scan);
    out.observations = detectors::toLandmarkObservations(seq, det, load);
    out.landmarks = det.association.landmarks.size();
  } else {
    for (const auto& stop : seq.stops) out.observations.commanded.push_back(stop.commanded);
    out.observations.range_min_m = seq.meta.range_min_m.value_or(0.0);
    out.observations.range_max_m = seq.meta.range_max_m.value_or(1e9);
  }
  out.observations.walls = detectors::wallsAtStops(seq, wallStops(ref), load, detection.detection);
  const double radius =
      detection.detection.landmark_radius_m.value_or(seq.meta.landmark_radius_m.value_or(0.0));
  out.known = calibration::knownReadings(out.observations, ref, radius);
  out.spans = calibration::spanReadings(out.observations, ref);
  return out;
}

void requireEveryDistanceFound(const calibration::ReferenceReadings& known,
                               const std::filesystem::path& ref_file) {
  std::string unmatched;
  std::size_t failures = 0;
  for (const auto& m : known.matches)
    if (!m.ok()) {
      if (failures++ < 5)
        unmatched += (unmatched.empty() ? "" : "; ") + std::string("distances[") +
                     std::to_string(m.entry) + "]: " + m.status;
    }
  if (failures > 5) unmatched += "; and " + std::to_string(failures - 5) + " more";
  if (failures > 0)
    throw DataError(ref_file.string(), "distances", unmatched,
                    "check the stop numbers (lidarcal info), give bearing_rad to pick the target, "
                    "or remove the entry");
}

void requireDistinctTargets(const calibration::ReferenceReadings& known,
                            const std::filesystem::path& ref_file) {
  const auto& ms = known.matches;
  for (std::size_t j = 1; j < ms.size(); ++j)
    for (std::size_t i = 0; i < j; ++i) {
      const calibration::ReferenceMatch &a = ms[i], &b = ms[j];
      if (!a.ok() || !b.ok() || a.stop != b.stop || a.target != b.target) continue;
      // One pole is one landmark id; one wall gives the same mean over the same scans.
      const bool pole = a.target == ReferenceTarget::landmark;
      if (pole ? a.landmark != b.landmark
               : (a.measured_m != b.measured_m || a.bearing_rad != b.bearing_rad))
        continue;
      throw InputError(
          ref_file.string(), "distances[" + std::to_string(b.entry) + "]",
          "names the same " +
              (pole ? "pole (landmark " + std::to_string(b.landmark) + ")" : std::string("wall")) +
              " at stop " + std::to_string(b.stop) + " as distances[" + std::to_string(a.entry) +
              "], so its readings would count twice",
          "give each target at a stop once: average repeated tape measurements into one entry, or "
          "give "
          "bearing_rad to pick another target (docs/FORMAT.md)");
    }
}

void requireEverySpanFound(const calibration::SpanReadings& spans,
                           const std::filesystem::path& ref_file) {
  std::string unmatched;
  std::size_t failures = 0;
  for (const auto& m : spans.matches)
    if (!m.ok() && failures++ < 5)
      unmatched += (unmatched.empty() ? "" : "; ") + std::string("spans[") +
                   std::to_string(m.entry) + "]." + m.field + ": " + m.status;
  if (failures > 5) unmatched += "; and " + std::to_string(failures - 5) + " more";
  if (failures > 0)
    throw DataError(ref_file.string(), "spans", unmatched,
                    "give each wall's normal direction in the sensor frame (degrees "
                    "counter-clockwise from the sensor's "
                    "forward axis, within 20 degrees; the walls seen are listed), check the stop "
                    "and distance_m, or "
                    "remove the entry (docs/FORMAT.md#wall-to-wall-spans)");
}

std::size_t measuredStops(const Reference& ref) {
  std::set<std::size_t> measured;
  for (const auto& d : ref.distances) measured.insert(d.stop);
  return measured.size();
}

SequenceCalibration calibrateSequenceWithReference(
    const ReferencedSequence& r, std::vector<calibration::ReferenceMatch>* matches,
    const StageProgress& on_scan, SpanReport* spans) {
  const io::Sequence& seq = r.seq;
  const Reference& ref = r.ref;
  const std::filesystem::path& ref_file = r.ref_file;
  const calibration::CalibrationConfig& config = r.config;
  if (ref.distances.empty() && ref.spans.empty())
    throw InputError(
        ref_file.string(), "distances",
        "is empty: calibrating against a reference needs measured distances at 3 or more stops, or "
        "wall-to-wall spans",
        "add the distances or spans you measured (docs/FORMAT.md, \"Reference measurements\")");
  ReferenceObservations ro =
      observeReference(seq, ref, referenceDetection(r.detection), scanLoader(seq), on_scan);
  if (matches) *matches = ro.known.matches;
  requireEveryDistanceFound(ro.known, ref_file);
  requireDistinctTargets(ro.known, ref_file);
  requireEverySpanFound(ro.spans, ref_file);
  SequenceCalibration out;
  out.observations = std::move(ro.observations);
  if (ref.spans.empty()) {
    out.model = calibration::calibrateWithReference(
        ro.known.readings, config, out.observations.range_min_m, out.observations.range_max_m);
    out.known = std::move(ro.known.readings);
  } else {
    const calibration::SpanProblem problem =
        calibration::spanProblem(ro.spans, ref, ro.known.readings);
    std::vector<calibration::SpanCheck> checks;
    out.model = calibration::calibrateWithSpans(out.observations, problem, ro.known.readings,
                                                config, &checks, &out.known);
    if (spans) *spans = SpanReport{std::move(ro.spans), std::move(checks)};
  }
  if (seq.meta.sensor_name) out.model.sensor_name = *seq.meta.sensor_name;
  const auto [fewest, most] = io::pointCountRange(seq);
  if (seq.meta.beams)
    out.model.beams = seq.meta.beams;
  else if (fewest == most && most > 0)
    out.model.beams = static_cast<int>(most);
  out.detections.association.assigned = out.known.size();
  return out;
}

SequenceCalibration calibrateSequenceWithSurvey(const ReferencedSequence& r,
                                                std::vector<detectors::SurveyMatch>* matches,
                                                const NamedProgress& progress) {
  const io::Sequence& seq = r.seq;
  const Reference& ref = r.ref;
  const std::filesystem::path& ref_file = r.ref_file;
  detectors::SequenceDetectionConfig det = r.detection;
  if (!det.detection.landmark_radius_m && !seq.meta.landmark_radius_m)
    if (const auto radius = detectors::surveyedRadius(ref.landmarks))
      det.detection.landmark_radius_m = *radius;
  calibration::CalibrationConfig cfg = r.config;
  for (const auto& s : ref.stops) cfg.joint.known_poses[s.stop] = s.pose;
  std::vector<detectors::SurveyMatch> found;
  const auto adjust = [&](const detectors::SequenceDetections& d,
                          calibration::CalibrationConfig& c) {
    found = detectors::matchSurvey(ref.landmarks, d.association.landmarks);
    std::string unmatched;
    for (const auto& m : found) {
      if (m.id != 0) {
        c.joint.known_centres[m.id] =
            Eigen::Vector2d(ref.landmarks[m.entry].x_m, ref.landmarks[m.entry].y_m);
        continue;
      }
      char text[160];
      std::snprintf(text, sizeof text, "%slandmarks[%zu] (%.3f, %.3f)",
                    unmatched.empty() ? "" : "; ", m.entry, ref.landmarks[m.entry].x_m,
                    ref.landmarks[m.entry].y_m);
      unmatched += text;
    }
    char why[96];
    std::snprintf(why, sizeof why, ": no detected landmark within %.1f m (%zu detected)",
                  detectors::kSurveyGateM, d.association.landmarks.size());
    if (!unmatched.empty())
      throw DataError(
          ref_file.string(), "landmarks", unmatched + why,
          "give the centres in the frame of the VIEWPOINTs (`lidarcal detect` lists the detected "
          "landmarks' positions), or remove the entry");
  };
  SequenceCalibration out = calibrateSequence(seq, det, cfg, progress, adjust);
  if (matches) *matches = found;
  return out;
}

SequenceCalibration calibrateSequenceWithDistancesAndSelf(
    const ReferencedSequence& r, std::vector<calibration::ReferenceMatch>* matches,
    std::vector<detectors::SurveyMatch>* survey, const NamedProgress& progress) {
  const io::Sequence& seq = r.seq;
  const Reference& ref = r.ref;
  const std::filesystem::path& ref_file = r.ref_file;
  if (r.config.method != calibration::Method::joint)
    throw InputError(
        ref_file.string(), "distances",
        "measured at only some stops (or given with surveyed landmarks or stops) are combined with "
        "the "
        "self-calibration in the joint refinement, which --method closed-form skips",
        "use --method joint, or --reference-fit distances to fit the measured distances alone");
  const ReferenceObservations ro =
      observeReference(seq, ref, referenceDetection(r.detection), scanLoader(seq));
  if (matches) *matches = ro.known.matches;
  requireEveryDistanceFound(ro.known, ref_file);
  requireDistinctTargets(ro.known, ref_file);
  calibration::CalibrationConfig cfg = r.config;
  cfg.joint.known_ranges = calibration::knownRanges(ro.known, ref);
  SequenceCalibration out =
      calibrateSequenceWithSurvey({seq, ref, ref_file, r.detection, cfg}, survey, progress);
  if (out.model.status.ok()) out.model.method = "joint+reference";
  // The measured entries were terms of the fit, none held out: REML counts the polynomial's
  // coefficients as fitted to them, so the discrepancy is estimated only where they outnumber them.
  if (out.model.status.ok()) {
    out.model.discrepancy = calibration::discrepancyOfMeasuredEntries(out.model, ro.known.readings);
    for (std::string& w : calibration::disagreeingEntryWarnings(out.model, ro.known.readings))
      out.model.warnings.push_back(std::move(w));
  }
  return out;
}

std::string surveyTable(const std::vector<detectors::SurveyMatch>& matches, const Reference& ref) {
  std::string t;
  if (!matches.empty())
    t += "surveyed landmarks held fixed (REF.json; off by: from the position detect found with the "
         "commanded poses "
         "and raw ranges):\n\n| entry | x_m | y_m | detected id | off by [m] "
         "|\n|---|---|---|---|---|\n";
  char row[160];
  for (const auto& m : matches) {
    std::snprintf(row, sizeof row, "| landmarks[%zu] | %.3f | %.3f | %d | %.3f |\n", m.entry,
                  ref.landmarks[m.entry].x_m, ref.landmarks[m.entry].y_m, m.id, m.distance_m);
    t += row;
  }
  if (!matches.empty()) t += "\n";
  if (!ref.stops.empty())
    t += "measured stop poses held fixed: " + std::to_string(ref.stops.size()) + "\n\n";
  return t;
}

}  // namespace lidarcal::pipeline
