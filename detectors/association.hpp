// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Association across stops, in world coordinates from each scan's commanded pose (VIEWPOINT):
//  1. at each stop (one pose: detections differ by noise only) the detections closer than
//     stop_link_distance_m form stop clusters, one detection per scan; a cluster is strong when
//     found in at least min_scan_fraction of the stop's scans (a pole is found in nearly every
//     scan, a box corner that looks round now and then is not);
//  2. stop by stop along the path, each strong stop cluster continues the track (an object
//     followed from stop to stop) with a strong sighting among its last 8 nearest to it, within
//     link_distance_m; pairs are taken closest first, one cluster per track and stop, so that
//     two poles closer than link_distance_m seen together stay two tracks; a strong cluster
//     that continues no track starts one. Comparing with the recent sightings follows a
//     landmark whose apparent position creeps from stop to stop (range bias changing with
//     distance, odometry drift) and tolerates one odd sighting;
//     When a strong cluster continuing one track also lies within link_distance_m of another
//     track's recent sightings, and the two tracks were never seen at one stop (close to each
//     other), they are one object found twice (a revisit, an odd sighting): they merge, as
//     single linkage would join them;
//  3. a weak stop cluster joins the track not seen strongly at this stop with a recent strong
//     sighting within stop_link_distance_m (closest pairs first);
//     Continuous motion (drift_per_m > 0: every scan its own pose): the reach of a track grows
//     with the distance the robot travelled since its last strong sighting, link_distance_m +
//     drift_per_m x travel (capped at max_link_distance_m), because the odometry's error between
//     two sightings of one pole grows with the motion between them (scene.hpp, OdometryNoise): a
//     pole seen again after a loop keeps its id instead of starting a new track;
//  4. tracks seen strongly at min_stops stops are the landmarks; the others (chair legs,
//     spurious circles) are discarded, and forgotten once unseen for forget_after_stops stops,
//     so that memory holds the landmarks and the recent objects, not the stops.
// The result does not depend on the order of the scans or of the detections in a scan (stops
// are taken in index order, the order of the path); ids are assigned by first sighting
// (smallest ScanDetections::scan_index), then by bearing in that scan (counter-clockwise from
// the sensor's x axis), then by world position. No ground truth is used.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "common/pose2.hpp"
#include "detectors/scan_detector.hpp"

namespace lidarcal::detectors {

struct AssociationConfig {
  /// Detections closer than this in the world frame belong to one landmark, metres. Must exceed
  /// the spread of one landmark's detections (range bias changing with distance, odometry error
  /// between consecutive stops) and stay below the distance between landmarks. Default 0.35.
  double link_distance_m = 0.35;
  /// Detections of one stop closer than this belong to one object, metres. Default 0.2.
  double stop_link_distance_m = 0.2;
  /// Shortest linking distance tried when splitting a component, metres. Default 0.05.
  double min_link_distance_m = 0.05;
  /// A landmark must be seen (strongly) at this many distinct stops (capped at the number of
  /// stops in the input). Default 3.
  int min_stops = 3;
  /// A stop sees a landmark strongly when at least this fraction of its scans detected it.
  /// Default 0.5.
  double min_scan_fraction = 0.5;
  /// A track not (yet) seen at min_stops stops is dropped once unseen for this many stops: its
  /// object is left behind on the path. Bounds memory on long sequences; an object revisited
  /// later than this before it reached min_stops starts a new track. Default 500.
  std::size_t forget_after_stops = 500;
  /// Landmarks too are dropped once unseen for this many stops (StopLinker::forgotten lists
  /// them; finish() no longer knows them). 0 (default): kept to the end, as a whole sequence's
  /// association needs. A watcher that runs for hours bounds its memory with it.
  std::size_t forget_landmarks_after_stops = 0;
  /// Continuous motion: growth of a track's reach per metre travelled since its last strong
  /// sighting (travel: path length plus 1 m per radian turned, StopLinker::moveTo), metres per
  /// metre. 0 (default): the reach stays link_distance_m (stop and go).
  double drift_per_m = 0.0;
  /// Largest reach with drift_per_m > 0, metres (link_distance_m when that is larger). Default 0.7.
  double max_link_distance_m = 0.7;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// One landmark over the whole sequence.
struct Landmark {
  int id = 0;                  ///< 1-based id, the `label` of its points
  double x_m = 0.0;            ///< mean world x of its detections (commanded poses), metres
  double y_m = 0.0;            ///< mean world y of its detections, metres
  std::size_t detections = 0;  ///< detections with this id
  /// stops that saw it strongly (in at least min_scan_fraction of their scans)
  std::size_t stops = 0;
  std::size_t first_scan = 0;  ///< smallest scan_index that saw it
  /// median radius of its detections, metres (detectSequence: known or jointly estimated)
  double radius_m = 0.0;
  /// radius_m was estimated jointly over its observations (landmark_radius.hpp)
  bool radius_estimated = false;
};

struct Association {
  std::vector<Landmark> landmarks;  ///< ids 1..L in this order
  /// Landmark id of each detection: ids[i][j] for detection j of input scan i; 0 = not a landmark.
  std::vector<std::vector<int>> ids;
  std::size_t detections = 0;  ///< detections in the input
  std::size_t assigned = 0;    ///< detections given an id
  /// detections in groups seen at too few stops (or weak and alone)
  std::size_t discarded_few_stops = 0;
  /// detections (or stop clusters) dropped as a second one of their scan (stop)
  std::size_t discarded_conflicts = 0;
  std::size_t discarded_components = 0;  ///< groups discarded for too few stops
};

/// Groups the detections of all scans into landmarks. viewpoints[i] is the commanded pose of scan
/// i. (Stage 1 per stop with clusterStop, then a StopLinker over the stops in index order.)
Association associate(const std::vector<ScanDetections>& scans,
                      const std::vector<Pose2>& viewpoints, const AssociationConfig& config);

// ---- The same in steps, for streaming: stage 1 needs the detections of one stop only;
// stages 2-4 (StopLinker) the stop clusters of one stop and the tracks alive. ----

/// Order-free identity of a detection: (scan_index, stop, bearing in [0, 2 pi), world x, world y).
using DetectionKey = std::tuple<std::size_t, std::size_t, double, double, double>;

/// Stage 1 summary: the detections of one object at one stop.
struct StopCluster {
  std::size_t stop = 0;
  bool strong = false;          ///< found in at least min_scan_fraction of the stop's scans
  double x_m = 0.0, y_m = 0.0;  ///< centroid of its detections, world frame, metres
  std::size_t detections = 0;   ///< one per scan at most
  double radius_m = 0.0;        ///< median radius of its detections, metres
  DetectionKey first;           ///< key of its first detection
};

/// The stop clusters of one stop.
using StopClusters = std::vector<StopCluster>;

/// Stage 1 at one stop: `scans` are all the scans of one stop (ScanDetections::stop equal),
/// viewpoints[i] the commanded pose of scans[i]. Appends the stop's clusters to `out`, ordered
/// by their first key (an order that depends only on the detections) and, when `cluster_of`
/// is given, sets (*cluster_of)[i][j] to the index in `out` of detection j of scans[i] (-1:
/// dropped as a second detection of its scan). Returns the number of detections dropped that way.
std::size_t clusterStop(const std::vector<const ScanDetections*>& scans,
                        const std::vector<Pose2>& viewpoints, const AssociationConfig& config,
                        StopClusters& out, std::vector<std::vector<int>>* cluster_of = nullptr);

/// A track's serial number: 1, 2, ... in order of creation; 0 for "no track".
using TrackSerial = std::uint64_t;

/// Landmark id of each track that became a landmark: (serial, id) pairs sorted by serial.
struct TrackIds {
  std::vector<std::pair<TrackSerial, int>> ids;
  /// The landmark id of track `serial`; 0 when it is no landmark (or serial is 0).
  int of(TrackSerial serial) const;
};

/// Landmark ids of one scan's detections: cluster_of[j] is detection j's index in its stop's
/// clusters (clusterStop) or -1, track_of[k] the track of cluster k (StopLinker::add).
std::vector<int> landmarkIds(const std::vector<int>& cluster_of,
                             const std::vector<TrackSerial>& track_of, const TrackIds& ids);

/// A sample of at most `capacity` items spread evenly over all items offered (every item while
/// fewer than `capacity` were offered; then every 2nd, 4th, ... one), in memory bounded by the
/// capacity whatever the number offered. Deterministic.
template <class T>
class EvenSample {
 public:
  explicit EvenSample(std::size_t capacity = 64) : capacity_(std::max<std::size_t>(capacity, 2)) {}
  void offer(T item) {
    if (offered_++ % stride_ != 0) return;
    kept_.push_back(std::move(item));
    if (kept_.size() < capacity_) return;
    std::size_t w = 0;  // keep items 0, 2, 4, ...: those at multiples of twice the stride
    for (std::size_t r = 0; r < kept_.size(); r += 2) kept_[w++] = std::move(kept_[r]);
    kept_.resize(w);
    stride_ *= 2;
  }
  const std::vector<T>& items() const { return kept_; }
  std::size_t offered() const { return offered_; }

 private:
  std::size_t capacity_, stride_ = 1, offered_ = 0;
  std::vector<T> kept_;
};

/// Stages 2-4 over the stops of a sequence, one stop at a time (association.hpp header).
/// Memory holds the tracks alive: the landmarks so far and the objects seen within the last
/// forget_after_stops stops.
class StopLinker {
 public:
  /// `stops`: the number of distinct stops in the whole input (those without detections
  /// included), which caps min_stops.
  StopLinker(const AssociationConfig& config, std::size_t stops);

  /// Links the clusters of the next stop (all of one stop, whose index exceeds the previous
  /// call's; clusterStop's order); `stage1_conflicts` is clusterStop's return for that stop.
  /// Returns each cluster's track (0: a weak cluster near no track).
  std::vector<TrackSerial> add(const StopClusters& clusters, std::size_t stage1_conflicts);

  /// The pose (VIEWPOINT) of the next stop, before its add(): the travel since the previous
  /// pose (path length plus 1 m per radian turned) grows the reach of the tracks not seen since
  /// (AssociationConfig::drift_per_m). Without calls the travel stays 0.
  void moveTo(const Pose2& pose);

  /// Tracks dropped by the last add() (forget_after_stops; landmarks with
  /// forget_landmarks_after_stops): they will not become landmarks, or are no longer.
  const std::vector<TrackSerial>& forgotten() const { return forgotten_; }
  /// Tracks merged by the last add(): (merged track, the track it joined), in order.
  const std::vector<std::pair<TrackSerial, TrackSerial>>& merged() const { return merged_; }

  /// The landmarks (Association::ids left empty) and the landmark id of each of their tracks.
  /// A landmark's position is the mean of its detections; its radius_m the median radius of its
  /// detections (each cluster's median weighted by its number of detections, over an even
  /// sample of at most 64 clusters).
  Association finish(TrackIds& ids) const;

  /// Tracks created so far (the serial of the last one).
  TrackSerial tracks() const { return next_serial_ - 1; }
  /// Tracks held now.
  std::size_t alive() const { return tracks_.size(); }

 private:
  struct Track {
    TrackSerial serial = 0;
    std::array<std::pair<double, double>, 8> recent{};  // last strong sightings (world, m), a ring
    std::size_t sightings = 0;  // strong sightings so far (recent holds the last 8)
    std::size_t last_stop = 0;  // stop of its last cluster, strong or weak
    double seen_at_m = 0.0;     // travel (moveTo) at its last strong sighting
    std::size_t strong_stops = 0;
    std::size_t detections = 0;
    double sum_x = 0.0, sum_y = 0.0;  // detections x cluster centroid, summed
    DetectionKey first;
    EvenSample<std::pair<double, std::size_t>> radii;  // (cluster median radius, detections)
    std::vector<TrackSerial> aliases;                  // tracks merged into this one
    // tracks seen close to it at one of its stops (sorted): never merged
    std::vector<TrackSerial> co_seen;
    bool dead = false;  // merged into another during this add()
    /// Distance from (x, y) to the nearest of its recent strong sightings, metres.
    double distanceTo(double x, double y) const;
  };
  /// The work of one add(): the stop's clusters, the track each joined (0: none yet) and which
  /// tracks were given a cluster at this stop.
  struct StopWork {
    const StopClusters& clusters;
    std::size_t stop;
    std::vector<TrackSerial> serial_of;
    std::vector<bool> taken;
  };
  std::size_t beginStop(const StopClusters& clusters);
  void join(StopWork& w, std::size_t k, Track& t);
  void assign(StopWork& w, bool strong, double fixed_reach);
  void startTracks(StopWork& w);
  std::size_t index(TrackSerial serial) const;
  void recordCoSeen(const StopWork& w);
  void mergeSplitTracks(StopWork& w);
  void dropMerged(StopWork& w);
  void forgetStale(std::size_t stop);
  void merge(Track& into, Track& from);
  /// How far from its recent sightings a strong cluster may continue track t, metres.
  double reach(const Track& t) const;
  AssociationConfig config_;
  std::size_t min_stops_ = 1;
  std::vector<Track> tracks_;  // in order of serial
  TrackSerial next_serial_ = 1;
  std::vector<TrackSerial> forgotten_;
  std::vector<std::pair<TrackSerial, TrackSerial>> merged_;
  bool started_ = false;
  std::size_t last_stop_ = 0;
  double travel_m_ = 0.0;      // odometer of moveTo
  std::optional<Pose2> pose_;  // the last pose given to moveTo
  Association totals_;         // counts only (detections, conflicts, discarded)
};

}  // namespace lidarcal::detectors
