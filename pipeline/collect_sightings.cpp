#include "pipeline/collect_sightings.hpp"

#include <cmath>

namespace lidarcal::pipeline {

LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const detectors::SequenceDetections& det) {
  return toLandmarkObservations(seq, det, [&seq](std::size_t i) { return io::readScan(seq.scans.at(i).path); });
}

LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const detectors::SequenceDetections& det,
                                            const detectors::ScanLoader& load) {
  LandmarkObservations obs;
  for (const auto& stop : seq.stops) obs.commanded.push_back(stop.commanded);
  if (det.known_radius_m) obs.landmark_radius_m = det.known_radius_m;
  obs.range_min_m = seq.meta.range_min_m.value_or(0.0);
  obs.range_max_m = seq.meta.range_max_m.value_or(1e9);
  // Point i is beam i only when every scan of the stop has the same number of points.
  std::vector<bool> same_beams(seq.stops.size(), true);
  for (std::size_t k = 0; k < seq.stops.size(); ++k)
    for (std::size_t i : seq.stops[k].scans)
      same_beams[k] = same_beams[k] && seq.scans[i].points == seq.scans[seq.stops[k].scans.front()].points;
  detectors::forEachScan(det, seq, load, [&](std::size_t i, const detectors::ScanDetections& sd, const std::vector<int>& ids) {
    bool any = false, kept_points = true;
    for (std::size_t j = 0; j < ids.size(); ++j)
      if (ids[j] > 0) any = true, kept_points = kept_points && sd.detections[j].inlier_xyi.size() == sd.detections[j].inliers.size();
    if (!any) return;
    // The inliers' coordinates kept by the detection, else the scan read again.
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
        const float x = kept_points ? d.inlier_xyi[k][0] : (*scan.cloud)[static_cast<std::size_t>(idx)].x;
        const float y = kept_points ? d.inlier_xyi[k][1] : (*scan.cloud)[static_cast<std::size_t>(idx)].y;
        const float in = kept_points ? d.inlier_xyi[k][2] : (*scan.cloud)[static_cast<std::size_t>(idx)].intensity;
        if (!std::isfinite(x)) continue;
        // The point's direction is its beam's direction: the sensor measures range along it.
        // An intensity of 0 (what a scan without one reads as) is none recorded.
        s.beams.push_back(BeamReading{std::atan2(static_cast<double>(y), static_cast<double>(x)),
                                      std::hypot(static_cast<double>(x), static_cast<double>(y)),
                                      same_beams[s.stop] ? static_cast<std::uint32_t>(idx) : kUnknownBeam,
                                      in > 0.0f ? static_cast<double>(in) : std::nan("")});
      }
      if (!s.beams.empty()) obs.sightings.push_back(std::move(s));
    }
  });
  return obs;
}

}  // namespace lidarcal::pipeline
