// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The two walls a wall-to-wall span names (REF.json `spans`, docs/FORMAT.md), found among the
// surfaces a stop sees (WallSighting::wall, detectors/wall_tracks.hpp), and what the scans read
// on them: per beam, the mean reading over the stop's scans. The fit that turns these into a
// range model is span_fit.hpp.
//
// A span is the distance between two parallel walls on opposite sides of the sensor, so it is
// the sum of the sensor's perpendicular distances to them, wherever between them it stands.
// Each wall is named by the direction of its normal from the sensor (within
// max_bearing_error_rad); among the surfaces there, the pair of parallel ones whose distances
// as read add up nearest the measured span is taken (a cabinet in front of a wall is told
// from the wall by the span).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common/landmark_observations.hpp"
#include "common/reference.hpp"

namespace lidarcal::calibration {

struct SpanConfig {
  /// A wall's normal must lie within this of the bearing REF.json gives, radians (a user
  /// judges a wall's direction to within a few tens of degrees; walls of a room are 90 degrees
  /// apart). Default 0.35 (20 degrees).
  double max_bearing_error_rad = 0.35;
  /// The two walls' normals must be opposite within this, radians: a span measured between
  /// walls that are not parallel depends on where it was measured. Default 0.087 (5 degrees).
  double max_parallel_error_rad = 0.087;
  /// The sum of the two walls' distances as read must lie within 0.1 m plus this fraction of
  /// the measured span. Default 0.25.
  double max_distance_error_fraction = 0.25;
  /// A surface seen in fewer than this fraction of its stop's scans is not a candidate. Default
  /// 0.25.
  double min_scan_fraction = 0.25;
  /// Beams that meet a wall within this angle of its normal are used, radians. Default 1.0 (57
  /// degrees).
  double max_incidence_rad = 1.0;
  void validate() const;  ///< throws std::invalid_argument naming the first bad field
};

/// A surface of one stop as the scans read it (raw line fits, sensor frame).
struct WallSurface {
  std::size_t stop = 0;     ///< stop index
  int wall = 0;             ///< its id at that stop (WallSighting::wall)
  double normal_rad = 0.0;  ///< circular mean of the sightings' normal directions, radians
  double distance_m = 0.0;  ///< mean perpendicular distance of the fitted lines, metres
  std::size_t scans = 0;    ///< scans in which it was seen
};

/// Every surface of every stop in `walls` (sightings with wall > 0), by stop, then id.
std::vector<WallSurface> wallSurfaces(const std::vector<WallSighting>& walls);

/// "-140 deg at 2.34 m, -50 deg at 3.44 m, ..." for the surfaces of `stop` (at most `limit`,
/// those seen in the most scans), for messages that ask the user to name a wall.
std::string surfaceList(const std::vector<WallSurface>& surfaces, std::size_t stop,
                        std::size_t limit = 8);

/// One wall of a span, as the fit sees it: its beams near the normal, each the mean of its
/// readings over the scans of the stop.
struct SpanWall {
  std::size_t stop = 0;     ///< stop index
  int wall = 0;             ///< surface id at that stop
  double normal_rad = 0.0;  ///< normal direction as read (raw line fits), radians
  double distance_m = 0.0;  ///< perpendicular distance as read (raw line fits), metres
  struct Beam {
    double angle_rad = 0.0;  ///< beam angle, sensor frame, radians
    double reading_m = 0.0;  ///< mean raw reading over the scans that saw the wall, metres
    std::size_t count = 0;   ///< readings averaged
    std::uint32_t beam = 0;  ///< beam index (kUnknownBeam when not comparable across scans)
  };
  /// within max_incidence_rad of the normal, read in at least half its scans
  std::vector<Beam> beams;
};

/// A key telling a beam from the others of its stop: its index, else (a sensor whose beam count
/// varies) its angle to 1e-5 rad.
long long beamKey(const BeamReading& b);

/// How one span was found in the data.
struct SpanMatch {
  std::size_t entry = 0;               ///< index into Reference::spans
  std::size_t stop = 0;                ///< its stop
  double reference_m = 0.0;            ///< the measured span, metres
  std::size_t wall_a = 0, wall_b = 0;  ///< indices into SpanReadings::walls (when ok)
  /// what the scans say: mean over the scans of the sum of the two lines' distances, metres
  double measured_m = 0.0;
  /// standard error of that mean over the scans (NaN with one scan), metres
  double measured_se_m = 0.0;
  std::size_t scans = 0;      ///< scans that saw both walls
  std::string status = "ok";  ///< ok, or why the span could not be used
  /// the REF.json field the failure concerns (e.g. "bearing_b_deg"), empty when ok
  std::string field;
  bool ok() const { return status == "ok"; }
};

struct SpanReadings {
  std::vector<SpanWall> walls;     ///< every wall some span uses, once
  std::vector<SpanMatch> matches;  ///< one per span, in order
};

/// Finds each span's two walls among the surfaces of its stop and gathers their beams.
SpanReadings spanReadings(const LandmarkObservations& obs, const Reference& ref,
                          const SpanConfig& config = {});

}  // namespace lidarcal::calibration
