// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/truth_evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "calibration/oracle.hpp"
#include "common/errors.hpp"

namespace lidarcal::calibration {

double commandedScale(const Truth& truth) {
  std::vector<Pose2> actual, commanded;
  for (const auto& s : truth.stops) {
    actual.push_back(s.actual);
    commanded.push_back(s.commanded);
  }
  return actual.size() >= 2 ? similarityScale(actual, commanded) : 1.0;
}

namespace {

void checkMatches(const io::Sequence& raw, const io::SimulationTruth& truth) {
  if (raw.scans.size() * truth.beams != truth.ranges.size())
    throw InputError(
        raw.dir.string(), "",
        "has " + std::to_string(raw.scans.size()) + " scans, the truth describes " +
            std::to_string(truth.ranges.size() / std::max<std::size_t>(truth.beams, 1)),
        "pass the truth.json of this very sequence");
}

}  // namespace

std::vector<RangePair> truthPairs(const io::Sequence& raw, const io::SimulationTruth& truth,
                                  double scale) {
  checkMatches(raw, truth);
  std::vector<RangePair> pairs;
  for (std::size_t k = 0; k < raw.stops.size(); ++k) {
    const auto& scans = raw.stops[k].scans;
    for (std::size_t pos = 0; pos < scans.size(); ++pos) {
      const std::size_t i = scans[pos];
      const io::Scan scan = io::readScan(raw.scans[i].path);
      for (std::size_t b = 0; b < scan.cloud->size() && b < truth.beams; ++b) {
        const auto& t = truth.at(i, b);
        const auto& p = (*scan.cloud)[b];
        if (t.target != io::TargetKind::landmark || !std::isfinite(p.x)) continue;
        const int part =
            scans.size() >= 3 ? static_cast<int>(pos % 3) : static_cast<int>((k + b) % 3);
        pairs.push_back({scale * t.range_m,
                         std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)), part});
      }
    }
  }
  return pairs;
}

std::vector<std::vector<double>> truthBatches(const io::Sequence& raw,
                                              const io::SimulationTruth& truth) {
  checkMatches(raw, truth);
  std::vector<std::vector<double>> batches;
  for (const auto& stop : raw.stops) {
    std::map<std::size_t, std::vector<double>> by_beam;
    for (std::size_t i : stop.scans) {
      const io::Scan scan = io::readScan(raw.scans[i].path);
      for (std::size_t b = 0; b < scan.cloud->size() && b < truth.beams; ++b) {
        const auto& p = (*scan.cloud)[b];
        if (truth.at(i, b).target == io::TargetKind::landmark && std::isfinite(p.x))
          by_beam[b].push_back(std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)));
      }
    }
    for (auto& [b, v] : by_beam) batches.push_back(std::move(v));
  }
  return batches;
}

namespace {

/// Truth, raw and corrected ranges of one class of beams.
struct Compared {
  std::vector<double> truth, raw, corrected;
  void add(double t, double r, double c) {
    truth.push_back(t);
    raw.push_back(r);
    corrected.push_back(c);
  }
  RangeComparison compare() const { return compareRanges(truth, raw, corrected); }
};

}  // namespace

Evaluation evaluate(const io::Sequence& raw, const io::SimulationTruth& truth,
                    const CorrectedRanges& corrected) {
  checkMatches(raw, truth);
  Compared landmarks, walls, all, beyond;
  Evaluation e;
  for (std::size_t i = 0; i < raw.scans.size(); ++i) {
    const io::Scan rs = io::readScan(raw.scans[i].path);
    const CorrectedScanRanges cor = corrected(i, rs);
    ++e.scans;
    for (std::size_t b = 0; b < rs.cloud->size() && b < truth.beams && b < cor.range_m.size();
         ++b) {
      const auto& t = truth.at(i, b);
      const auto& p = (*rs.cloud)[b];
      if (!std::isfinite(p.x) || !std::isfinite(t.range_m)) continue;
      const double c = cor.range_m[b];
      if (!std::isfinite(c)) {
        ++e.lost;
        continue;
      }
      const double r = std::hypot(static_cast<double>(p.x), static_cast<double>(p.y));
      all.add(t.range_m, r, c);
      if (t.target == io::TargetKind::landmark)
        landmarks.add(t.range_m, r, c);
      else if (t.target == io::TargetKind::wall)
        walls.add(t.range_m, r, c);
      if (b < cor.beyond.size() && cor.beyond[b]) beyond.add(t.range_m, r, c);
    }
  }
  e.landmarks = landmarks.compare();
  e.walls = walls.compare();
  e.all = all.compare();
  e.beyond = beyond.compare();
  return e;
}

Evaluation evaluate(const io::Sequence& corrected, const io::Sequence& raw,
                    const io::SimulationTruth& truth) {
  if (corrected.scans.size() != raw.scans.size())
    throw InputError(corrected.dir.string(), "",
                     "has " + std::to_string(corrected.scans.size()) + " scans, the raw sequence " +
                         std::to_string(raw.scans.size()),
                     "evaluate the output of `lidarcal correct` on this raw sequence");
  return evaluate(raw, truth, [&](std::size_t i, const io::Scan& rs) {
    if (raw.scans[i].name() != corrected.scans[i].name())
      throw InputError(corrected.scans[i].path, "",
                       "does not match the raw scan " + raw.scans[i].path,
                       "the corrected and raw sequences must hold the same file names");
    const io::Scan cs = io::readScan(corrected.scans[i].path);
    if (cs.cloud->size() != rs.cloud->size())
      throw InputError(corrected.scans[i].path, "POINTS", "differs from the raw scan",
                       "re-run lidarcal correct");
    CorrectedScanRanges r;
    r.range_m.resize(cs.cloud->size());
    for (std::size_t b = 0; b < r.range_m.size(); ++b) {
      const auto& q = (*cs.cloud)[b];
      r.range_m[b] = std::isfinite(q.x)
                         ? std::hypot(static_cast<double>(q.x), static_cast<double>(q.y))
                         : std::nan("");
    }
    for (const io::PointCorrection c : cs.correction)
      r.beyond.push_back(c == io::PointCorrection::extrapolated || c == io::PointCorrection::raw);
    return r;
  });
}

Evaluation evaluate(const CalibrationModel& model, InversionMethod method, Outside outside,
                    const io::Sequence& raw, const io::SimulationTruth& truth) {
  const ReadingCorrector correct = readingCorrector(model, method, outside);
  return evaluate(raw, truth, [&](std::size_t, const io::Scan& rs) {
    CorrectedScanRanges r;
    r.range_m.assign(rs.cloud->size(), std::nan(""));
    r.beyond.assign(rs.cloud->size(), false);
    for (std::size_t b = 0; b < r.range_m.size(); ++b) {
      const auto& p = (*rs.cloud)[b];
      if (!std::isfinite(p.x)) continue;
      const CorrectedReading c =
          correct(std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)));
      r.range_m[b] = c.range_m;
      r.beyond[b] = c.fate != ReadingFate::corrected && c.fate != ReadingFate::unresolved;
    }
    return r;
  });
}

CalibrationModel calibrateOracle(const io::Sequence& raw, const io::SimulationTruth& truth,
                                 double scale, const CalibrationConfig& config) {
  const auto pairs = truthPairs(raw, truth, scale);
  const auto& sensor = truth.truth.scene.sensor.range;
  CalibrationModel m = calibrateAgainstTruth(pairs, config, truthBatches(raw, truth),
                                             sensor.range_min_m, sensor.range_max_m);
  m.method = scale == 1.0 ? "oracle" : "oracle-commanded";
  m.beams = truth.truth.scene.sensor.beams;
  m.sensor_name = truth.truth.scene.sensor.name;
  for (const auto& s : truth.truth.stops)
    m.stop_poses.push_back(scale == 1.0 ? s.actual : s.commanded);
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

}  // namespace lidarcal::calibration
