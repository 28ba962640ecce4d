// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Mixed pixels beside a pole: the beam just outside a circle's inliers that reads between the
// pole and the surface behind it, kept when no nearby scan sees a surface at its point (what is
// behind a pole is seen again, a mixed pixel's reading falls anywhere in between).

#include <cstddef>
#include <optional>
#include <vector>

#include "common/landmark_observations.hpp"
#include "common/pose2.hpp"
#include "detectors/scan_detector.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/pcd_scan.hpp"
#include "io/sequence.hpp"

namespace lidarcal::detectors {

/// The reading of the point next to a circle's outermost inlier `edge` on the side `step` (+1 or
/// -1; points taken modulo the scan's size), marked `beside`, when it lies between the pole and
/// what is behind it: at least the pole's radius and twice the inlier threshold t beyond the
/// inlier's reading, and 3 t short of the background, which is the surface of the next two
/// points out extended to this beam (the nearer of that line and the next point's reading). The
/// four points must be evenly spaced in angle (within a quarter of a step), so a cloud without
/// its missing returns is judged right too. A clean scan puts almost no reading there: a beam
/// past the pole reads the background, one on it reads the pole. A pole across a full scan's seam
/// is looked beside too: its inliers run along the arc (n-2, n-1, 0, 1), so their ends are its
/// edges.
std::optional<BeamReading> readingBetweenPoleAndBackground(const io::Scan& scan, int edge, int step,
                                                           double radius_m,
                                                           const DetectionConfig& config);

/// A reading between a pole and its background, waiting for the check that nothing is there.
struct BesideCandidate {
  std::size_t sighting = 0;  ///< in LandmarkObservations::sightings
  bool front = false;        ///< before the sighting's first beam (else after its last)
  BeamReading reading;       ///< the reading beside the pole (BeamReading::beside set)
};

/// A scan's returns in polar form, sorted by angle.
struct PolarScan {
  std::vector<double> angle_rad;  ///< beam angle of each return, ascending, radians (sensor frame)
  std::vector<double> range_m;    ///< its range, metres
};

/// The scan's returns (points with finite x and y) in polar form, sorted by angle.
PolarScan polarScan(const io::Scan& scan);

/// Whether a scan taken at `from` sees a surface at world point (x, y): one of the two returns
/// on each side of that direction reads its distance within `tolerance_m`.
bool seesPoint(const PolarScan& scan, const Pose2& from, double x, double y, double tolerance_m);

/// Keeps the candidates that no scan within `window` of theirs (the poses as commanded) sees
/// again within 2 t of their point (t the inlier threshold at its range), and puts them into
/// their sightings of `obs` (at the front or the back of its beams).
void addLoneCandidates(const io::Sequence& seq, const ScanLoader& load, const DetectionConfig& dc,
                       std::vector<BesideCandidate> candidates, std::size_t window,
                       LandmarkObservations& obs);

}  // namespace lidarcal::detectors
