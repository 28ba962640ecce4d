#include "pipeline/stages.hpp"

#include <algorithm>
#include <cmath>

#include "calibration/filtering.hpp"
#include "common/errors.hpp"
#include "pipeline/landmark_observations.hpp"

namespace lidarcal::pipeline {

SequenceCalibration calibrateSequence(const io::Sequence& seq, const detectors::SequenceDetectionConfig& detection,
                                      const calibration::CalibrationConfig& config, const StageProgress& on_scan) {
  SequenceCalibration out;
  out.detections = detectors::detectSequence(seq, detection, on_scan);
  out.observations = toLandmarkObservations(seq, out.detections);
  if (!seq.meta.range_max_m) {
    // No sensor window in sequence.json: take the largest landmark reading, with margin.
    double max_reading = 0.0;
    for (const auto& s : out.observations.sightings)
      for (const auto& b : s.beams) max_reading = std::max(max_reading, b.range_m);
    out.observations.range_max_m = max_reading > 0.0 ? 1.25 * max_reading : 1.0;
  }
  out.model = calibration::calibrate(out.observations, config);
  if (seq.meta.sensor_name) out.model.sensor_name = *seq.meta.sensor_name;
  if (seq.meta.beams) out.model.beams = seq.meta.beams;
  else if (!seq.scans.empty()) out.model.beams = static_cast<int>(seq.scans.front().points);
  if (out.model.status == "ok" && out.detections.association.landmarks.empty())
    out.model.message += (out.model.message.empty() ? "" : "; ") + out.detections.note;
  return out;
}

CalibrationModel calibrateOracle(const io::Sequence& raw, const SimulationTruth& truth, double scale,
                                 const calibration::CalibrationConfig& config) {
  const auto pairs = truthPairs(raw, truth, scale);
  const auto& sensor = truth.truth.scene.sensor.range;
  CalibrationModel m =
      calibration::calibrateAgainstTruth(pairs, config, truthBatches(raw, truth), sensor.range_min_m, sensor.range_max_m);
  m.method = scale == 1.0 ? "oracle" : "oracle-commanded";
  m.beams = truth.truth.scene.sensor.beams;
  m.sensor_name = truth.truth.scene.sensor.name;
  for (const auto& s : truth.truth.stops) m.stop_poses.push_back(scale == 1.0 ? s.actual : s.commanded);
  for (std::size_t i = 0; i < truth.truth.scene.landmarks.size(); ++i) {
    const auto& c = truth.truth.scene.landmarks[i];
    CalibratedLandmark l;
    l.id = static_cast<int>(i) + 1;
    l.x_m = c.x_m;
    l.y_m = c.y_m;
    l.radius_m = c.radius_m;
    m.landmarks.push_back(l);
  }
  return m;
}

void checkModelFits(const CalibrationModel& model, const io::Sequence& seq, const std::filesystem::path& model_file) {
  const std::string where = model_file.string();
  if (model.status != "ok")
    throw DataError(where, "diagnostics.status", "the model is not usable (" + model.status + "): " + model.message,
                    "calibrate again with more landmarks or stops");
  if (model.beams && !seq.scans.empty()) {
    for (const auto& h : seq.scans)
      if (h.points != static_cast<std::size_t>(*model.beams))
        throw InputError(h.path.string(), "POINTS",
                         "has " + std::to_string(h.points) + " beams, the model " + where + " was calibrated on a sensor with " +
                             std::to_string(*model.beams),
                         "use a model calibrated on this sensor");
  }
  const auto& m = seq.meta;
  auto differs = [](double a, double b) { return std::abs(a - b) > 1e-6 * std::max(1.0, std::abs(b)); };
  if ((m.range_min_m && differs(*m.range_min_m, model.model.range_min_m)) ||
      (m.range_max_m && differs(*m.range_max_m, model.model.range_max_m)))
    throw InputError(where, "sensor.range_min_m/range_max_m",
                     "the model's range limits differ from the sequence's (" + seq.dir.string() + "/sequence.json)",
                     "the model belongs to another sensor; calibrate this one");
  double at = 0.0;
  if (!calibration::invertsReadingWindow(model.model.bias, model.model.range_min_m, model.model.range_max_m, &at))
    throw DataError(where, "bias.alpha",
                    "the bias polynomial stops increasing at d = " + std::to_string(at) +
                        " m before its readings reach the range limit, so a reading maps to more than one distance",
                    "calibrate with a lower --max-order or with landmarks covering the whole range");
}

CorrectionStats correctSequence(const io::Sequence& seq, const CalibrationModel& model,
                                calibration::InversionMethod method, const std::filesystem::path& out_dir,
                                io::PcdEncoding encoding, const StageProgress& on_scan) {
  const calibration::RangeInverter inverter(model.model, calibration::inversionWindow(model.model, method));
  CorrectionStats stats;
  for (std::size_t i = 0; i < seq.scans.size(); ++i) {
    const io::Scan scan = io::readScan(seq.scans[i].path);
    calibration::FilteringStats f;
    const io::Scan out = calibration::correctScan(scan, inverter, &f);
    io::writeScan(out_dir / seq.scans[i].path.filename(), out, encoding);
    ++stats.scans;
    stats.points += f.points;
    stats.corrected += f.corrected;
    stats.unresolved += f.unresolved;
    if (on_scan) on_scan(i + 1, seq.scans.size());
  }
  const auto meta = seq.dir / "sequence.json";
  std::error_code ec;
  if (std::filesystem::exists(meta, ec)) io::writeSequenceMeta(out_dir / "sequence.json", seq.meta);
  return stats;
}

}  // namespace lidarcal::pipeline
