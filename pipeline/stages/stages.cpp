// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/stages.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "calibration/filtering.hpp"
#include "common/errors.hpp"
#include "common/parallel.hpp"
#include "common/plural.hpp"
#include "detectors/sightings.hpp"

namespace lidarcal::pipeline {

SequenceCalibration calibrateSequence(const io::Sequence& seq,
                                      const detectors::SequenceDetectionConfig& detection,
                                      const calibration::CalibrationConfig& config,
                                      const NamedProgress& progress,
                                      const CalibrationAdjust& adjust) {
  SequenceCalibration out;
  // Triangulation needs every landmark seen from min_stops stops: with fewer stops in the whole
  // sequence there is nothing to detect for.
  const int min_stops = config.triangulation.min_stops;
  if (seq.stops.size() < static_cast<std::size_t>(min_stops)) {
    out.model.status.code = StatusCode::too_few_stops;
    out.model.status.message =
        "the sequence has " + plural(seq.stops.size(), "stop") +
        " (consecutive scans with one VIEWPOINT form a stop) and each landmark must be "
        "triangulated from at least " +
        std::to_string(min_stops) + " stops: record scans at " + std::to_string(min_stops) +
        " or more stops along a line, each with its own VIEWPOINT";
    return out;
  }
  // A sensor that only turned or stood still cannot triangulate: say so before detecting.
  {
    std::vector<Pose2> poses;
    poses.reserve(seq.stops.size());
    for (const auto& stop : seq.stops) poses.push_back(stop.commanded);
    if (const auto problem = calibration::baselineProblem(poses, config)) {
      out.model.status.code = StatusCode::no_baseline;
      out.model.status.message = *problem;
      return out;
    }
  }
  out.detections =
      detectors::detectSequence(seq, detection, [&](std::size_t done, std::size_t total) {
        if (progress) progress("detect", done, total);
      });
  out.observations = detectors::toLandmarkObservations(seq, out.detections);
  if (!seq.meta.range_max_m) {
    // No sensor window in sequence.json: take the largest landmark reading, with margin.
    double max_reading = 0.0;
    for (const auto& s : out.observations.sightings)
      for (const auto& b : s.beams) max_reading = std::max(max_reading, b.range_m);
    out.observations.range_max_m = max_reading > 0.0 ? 1.25 * max_reading : 1.0;
  }
  calibration::CalibrationConfig reporting = config;
  if (adjust) adjust(out.detections, reporting);
  reporting.progress = [&](const char* stage, std::size_t done, std::size_t total) {
    if (config.progress) config.progress(stage, done, total);
    if (progress) progress(stage, done, total);
  };
  out.model = calibration::calibrate(out.observations, reporting);
  if (seq.meta.sensor_name) out.model.sensor_name = *seq.meta.sensor_name;
  // A beam count only when every scan has it: a sensor whose count varies (YDLIDAR X4) gets a
  // model without one, which `correct` applies to any scan.
  const auto [fewest, most] = io::pointCountRange(seq);
  if (seq.meta.beams)
    out.model.beams = seq.meta.beams;
  else if (fewest == most && most > 0)
    out.model.beams = static_cast<int>(most);
  if (out.detections.association.landmarks.empty())
    out.model.status.message = out.detections.note +
                               (out.model.status.message.empty() ? "" : "; ") +
                               out.model.status.message;
  return out;
}

std::string beamCountWarning(const io::Sequence& seq) {
  const auto [fewest, most] = io::pointCountRange(seq);
  if (fewest == most) return {};
  return seq.dir.string() + ": the number of points per scan varies from " +
         std::to_string(fewest) + " to " + std::to_string(most) +
         ": point i is not the same beam in every scan, so the noise-exponent test (Alhashimi et "
         "al. 2016) uses only the stops whose "
         "scans agree, and the model records no beam count. Landmark fits are not affected. If the "
         "scans come from "
         "different sensors, split them into one sequence per sensor";
}

namespace {

void checkModelStatus(const CalibrationModel& model, const std::string& where) {
  if (!model.status.ok())
    throw DataError(where, "diagnostics.status",
                    "the model is not usable (" + std::string(model.status.name()) + ")" +
                        (model.status.message.empty() ? "" : ": " + model.status.message),
                    "calibrate again with more landmarks or stops");
}

void checkBiasInvertible(const CalibrationModel& model, const std::string& where,
                         calibration::Outside outside) {
  double at = 0.0;
  const BiasPolynomial& f = model.model.bias;
  if (model.fitted_range_m && outside != calibration::Outside::extrapolate) {
    // Only the fitted range is corrected: f must rise over it.
    const auto [lo, hi] = *model.fitted_range_m;
    if (!calibration::isMonotone(f, lo, hi, &at)) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "the bias polynomial stops increasing at d = %.3f m inside its fitted range "
                    "%.3f-%.3f m, so a "
                    "reading maps to more than one distance",
                    at, lo, hi);
      throw DataError(where, "bias.alpha", text, "calibrate with a lower --max-order");
    }
    return;
  }
  if (!calibration::invertsReadingWindow(f, model.model.range_min_m, model.model.range_max_m,
                                         &at)) {
    // Where f stops rising (first d with f'(d) <= 0), for the message.
    const int steps = 4000;
    double peak = -1.0;
    for (int i = 0; i <= steps && peak < 0.0; ++i) {
      const double d = at * i / steps;
      if (f.derivative(d) <= 0.0) peak = d;
    }
    char text[256];
    if (peak >= 0.0)
      std::snprintf(text, sizeof text,
                    "the bias polynomial stops increasing at d = %.3f m (reading %.3f m), below "
                    "the range limit %.3f m, "
                    "so a reading maps to more than one distance",
                    peak, f(peak), model.model.range_max_m);
    else
      std::snprintf(text, sizeof text,
                    "the bias polynomial does not reach the range limit %.3f m (at d = %.1f m it "
                    "reads %.3f m): readings "
                    "near the limit have no distance",
                    model.model.range_max_m, at, f(at));
    throw DataError(
        where, "bias.alpha", text,
        "calibrate with a lower --max-order or with landmarks covering the whole range");
  }
}

}  // namespace

calibration::ReadingCorrector modelCorrector(const CalibrationModel& model,
                                             calibration::InversionMethod method,
                                             calibration::Outside outside,
                                             const std::filesystem::path& model_file) {
  try {
    return calibration::readingCorrector(model, method, outside);
  } catch (const std::invalid_argument& e) {
    throw InputError(model_file.string(),
                     "--inversion " + std::string(calibration::toString(method)),
                     std::string("the model cannot be inverted this way (") + e.what() + ")",
                     "use --inversion ls, or a model fitted with the squared noise law for ml");
  }
}

void checkModelInvertible(const CalibrationModel& model, const std::filesystem::path& model_file,
                          calibration::Outside outside) {
  checkModelStatus(model, model_file.string());
  checkBiasInvertible(model, model_file.string(), outside);
}

void checkModelBeams(const CalibrationModel& model, std::size_t beams, const std::string& where,
                     const std::filesystem::path& model_file) {
  if (model.beams && beams != static_cast<std::size_t>(*model.beams))
    throw InputError(where, "POINTS",
                     "has " + std::to_string(beams) + " beams, the model " + model_file.string() +
                         " was calibrated on a sensor with " + std::to_string(*model.beams),
                     "use a model calibrated on this sensor");
}

std::string checkModelFitsSensor(const CalibrationModel& model, const SensorFacts& facts,
                                 const std::filesystem::path& model_file, bool force,
                                 calibration::Outside outside) {
  const std::string where = model_file.string();
  checkModelStatus(model, where);
  std::string warning;
  if (facts.sensor_name && !model.sensor_name.empty() && *facts.sensor_name != model.sensor_name)
    throw InputError(where, "sensor_name",
                     "the model was calibrated on '" + model.sensor_name + "', the " + facts.noun +
                         " comes from '" + *facts.sensor_name + "' (" + facts.source + ")",
                     "the model belongs to another sensor; calibrate this one");
  auto differs = [](double a, double b) {
    return std::abs(a - b) > 1e-6 * std::max(1.0, std::abs(b));
  };
  if ((facts.range_min_m && differs(*facts.range_min_m, model.model.range_min_m)) ||
      (facts.range_max_m && differs(*facts.range_max_m, model.model.range_max_m))) {
    char values[160];
    std::snprintf(values, sizeof values, "%g-%g m against %g-%g m", model.model.range_min_m,
                  model.model.range_max_m, facts.range_min_m.value_or(model.model.range_min_m),
                  facts.range_max_m.value_or(model.model.range_max_m));
    const std::string limits = "the model's range limits differ from the " + facts.noun +
                               "'s: " + std::string(values) + " (" + facts.source + ")";
    const std::string same = model.sensor_name.empty() ? "" : " ('" + model.sensor_name + "')";
    if (!force)
      throw InputError(
          where, "sensor.range_min_m/range_max_m", limits,
          "if this is the same sensor" + same +
              " with other limits set, pass --force to apply the model anyway (readings outside "
              "the "
              "model's limits are left without a distance); otherwise the model belongs to another "
              "sensor: calibrate this one");
    warning =
        limits + "; applied anyway (--force): readings outside the model's limits get no distance";
  }
  checkBiasInvertible(model, where, outside);
  return warning;
}

std::string checkModelFits(const CalibrationModel& model, const io::Sequence& seq,
                           const std::filesystem::path& model_file, bool force,
                           calibration::Outside outside) {
  checkModelStatus(model, model_file.string());
  for (const auto& h : seq.scans) checkModelBeams(model, h.points, h.path, model_file);
  const auto& m = seq.meta;
  return checkModelFitsSensor(model,
                              {m.sensor_name, m.range_min_m, m.range_max_m,
                               (seq.dir / "sequence.json").string(), "sequence"},
                              model_file, force, outside);
}

CorrectionStats correctSequence(const io::Sequence& seq, const CalibrationModel& model,
                                const std::filesystem::path& out_dir, const SequenceCorrection& how,
                                const StageProgress& on_scan) {
  const calibration::ReadingCorrector correct =
      calibration::readingCorrector(model, how.method, how.outside);
  CorrectionStats stats;
  // A window of scans at a time on `threads` threads (each scan read, corrected and written on
  // its own); the counts added up and the progress told in scan order.
  const int t = threadsFor(how.threads);
  const std::size_t n = seq.scans.size(), window = 16 * static_cast<std::size_t>(t);
  std::vector<calibration::FilteringStats> f(window);
  for (std::size_t first = 0; first < n; first += window) {
    const std::size_t count = std::min(window, n - first);
    parallelFor(count, t, [&](std::size_t k) {
      const std::size_t i = first + k;
      const io::Scan scan = io::readScan(seq.scans[i].path);
      f[k] = calibration::FilteringStats{};
      io::writeScan(out_dir / seq.scans[i].name(), calibration::correctScan(scan, correct, &f[k]),
                    how.encoding);
    });
    for (std::size_t k = 0; k < count; ++k) {
      ++stats.scans;
      stats += f[k];
    }
    if (on_scan) on_scan(first + count, n);
  }
  const auto meta = seq.dir / "sequence.json";
  std::error_code ec;
  if (std::filesystem::exists(meta, ec)) io::writeSequenceMeta(out_dir / "sequence.json", seq.meta);
  return stats;
}

}  // namespace lidarcal::pipeline
