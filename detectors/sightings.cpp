// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/sightings.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "detectors/mixed_pixels.hpp"

namespace lidarcal::detectors {

BeamReading beamReading(float x, float y, float intensity, std::uint32_t beam) {
  return BeamReading{std::atan2(static_cast<double>(y), static_cast<double>(x)),
                     std::hypot(static_cast<double>(x), static_cast<double>(y)), beam,
                     intensity > 0.0f ? static_cast<double>(intensity) : std::nan("")};
}

std::optional<BeamReading> pointReading(const io::Scan& scan, long i) {
  const auto& p = (*scan.cloud)[static_cast<std::size_t>(i)];
  if (!std::isfinite(p.x) || !std::isfinite(p.y)) return std::nullopt;
  return beamReading(p.x, p.y, p.intensity, static_cast<std::uint32_t>(i));
}

LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const SequenceDetections& det,
                                            const SightingOptions& options) {
  return toLandmarkObservations(
      seq, det, [&seq](std::size_t i) { return io::readScan(seq.scans.at(i).path); }, options);
}

LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const SequenceDetections& det,
                                            const ScanLoader& load,
                                            const SightingOptions& options) {
  LandmarkObservations obs;
  for (const auto& stop : seq.stops) obs.commanded.push_back(stop.commanded);
  if (det.known_radius_m) obs.landmark_radius_m = det.known_radius_m;
  obs.range_min_m = seq.meta.range_min_m.value_or(0.0);
  obs.range_max_m = seq.meta.range_max_m.value_or(1e9);
  // Point i is beam i only when every scan of the stop has the same number of points.
  std::vector<bool> same_beams(seq.stops.size(), true);
  for (std::size_t k = 0; k < seq.stops.size(); ++k)
    for (std::size_t i : seq.stops[k].scans)
      same_beams[k] =
          same_beams[k] && seq.scans[i].points == seq.scans[seq.stops[k].scans.front()].points;
  std::vector<BesideCandidate> beside;
  forEachScan(
      det, seq, load, [&](std::size_t i, const ScanDetections& sd, const std::vector<int>& ids) {
        bool any = false, kept_points = true;
        for (std::size_t j = 0; j < ids.size(); ++j)
          if (ids[j] > 0)
            any = true, kept_points = kept_points && sd.detections[j].inlier_xyi.size() ==
                                                         sd.detections[j].inliers.size();
        if (!any) return;
        // The inliers' coordinates kept by the detection, else the scan read again.
        if (options.mixed_pixel_candidates) kept_points = false;
        const io::Scan scan = kept_points ? io::Scan{} : load(i);
        for (std::size_t j = 0; j < sd.detections.size(); ++j) {
          if (ids[j] <= 0) continue;
          const auto& d = sd.detections[j];
          Sighting s;
          s.stop = seq.stopOf(i);
          s.scan = i;
          s.landmark = ids[j];
          s.bearing_rad = d.bearing_rad;
          s.centre_range_m = d.range_m;
          s.radius_m = d.radius_m;
          for (std::size_t k = 0; k < d.inliers.size(); ++k) {
            const auto idx = d.inliers[k];
            const float x =
                kept_points ? d.inlier_xyi[k][0] : (*scan.cloud)[static_cast<std::size_t>(idx)].x;
            const float y =
                kept_points ? d.inlier_xyi[k][1] : (*scan.cloud)[static_cast<std::size_t>(idx)].y;
            const float in = kept_points ? d.inlier_xyi[k][2]
                                         : (*scan.cloud)[static_cast<std::size_t>(idx)].intensity;
            if (!std::isfinite(x)) continue;
            s.beams.push_back(beamReading(
                x, y, in, same_beams[s.stop] ? static_cast<std::uint32_t>(idx) : kUnknownBeam));
          }
          if (s.beams.empty()) continue;
          if (options.mixed_pixel_candidates)
            for (const bool front : {true, false})
              if (auto r = readingBetweenPoleAndBackground(
                      scan, front ? d.inliers.front() : d.inliers.back(), front ? -1 : 1,
                      d.radius_m, det.replay.detection)) {
                if (!same_beams[s.stop]) r->beam = kUnknownBeam;
                beside.push_back({obs.sightings.size(), front, *r});
              }
          obs.sightings.push_back(std::move(s));
        }
      });
  if (!beside.empty())
    addLoneCandidates(seq, load, det.replay.detection, std::move(beside), options.persistence_scans,
                      obs);
  // Within a scan by landmark id, not in the detector's order: a fit under a pose per scan sums
  // its terms in this order, and on a drive with a hidden effect the same sightings listed in
  // another order (a pole across the scan's seam moved from first to last) reached baselines
  // 440 nats apart (a yawed thin-pole drive). Their order is a function of what was seen.
  std::stable_sort(obs.sightings.begin(), obs.sightings.end(),
                   [](const Sighting& a, const Sighting& b) {
                     return a.scan != b.scan ? a.scan < b.scan : a.landmark < b.landmark;
                   });
  return obs;
}

}  // namespace lidarcal::detectors
