// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/association.hpp"
#include "common/stats_util.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>
#include <tuple>

#include <pcl/kdtree/kdtree_flann.h>

namespace lidarcal::detectors {

void AssociationConfig::validate() const {
  auto fail = [](const char* field, const char* what) {
    throw std::invalid_argument(std::string("AssociationConfig.") + field + ": " + what);
  };
  if (!(link_distance_m > 0.0) || !std::isfinite(link_distance_m))
    fail("link_distance_m", "must be > 0");
  if (!(stop_link_distance_m > 0.0) || !std::isfinite(stop_link_distance_m))
    fail("stop_link_distance_m", "must be > 0");
  if (!(min_link_distance_m > 0.0 && min_link_distance_m <= link_distance_m))
    fail("min_link_distance_m", "must be in (0, link_distance_m]");
  if (min_stops < 1) fail("min_stops", "must be >= 1");
  if (!(min_scan_fraction >= 0.0 && min_scan_fraction <= 1.0))
    fail("min_scan_fraction", "must be in [0, 1]");
  if (!(drift_per_m >= 0.0) || !std::isfinite(drift_per_m)) fail("drift_per_m", "must be >= 0");
  if (!(max_link_distance_m > 0.0) || !std::isfinite(max_link_distance_m))
    fail("max_link_distance_m", "must be > 0");
}

namespace {

using Key = DetectionKey;

/// A point to link: a detection (stage 1) or a stop cluster (stage 2).
struct Node {
  double x = 0.0, y = 0.0;   // world position, metres
  std::size_t conflict = 0;  // two nodes with the same value may not share a group (scan, or stop)
  Key key;
};

struct UnionFind {
  std::vector<std::size_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::size_t find(std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void join(std::size_t a, std::size_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

void sortByKey(const std::vector<Node>& nodes, std::vector<std::size_t>& g) {
  std::sort(g.begin(), g.end(), [&](auto a, auto b) { return nodes[a].key < nodes[b].key; });
}

/// Connected components of the graph "closer than eps" over `members` (a FLANN kd-tree radius
/// search per node). Members sorted by key, components by their first member's key.
std::vector<std::vector<std::size_t>> components(const std::vector<Node>& nodes,
                                                 const std::vector<std::size_t>& members,
                                                 double eps) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(members.size());
  for (auto m : members)
    cloud->push_back(
        pcl::PointXYZ(static_cast<float>(nodes[m].x), static_cast<float>(nodes[m].y), 0.0f));
  UnionFind uf(members.size());
  if (!members.empty()) {
    pcl::KdTreeFLANN<pcl::PointXYZ> tree;
    tree.setInputCloud(cloud);
    pcl::Indices found;
    std::vector<float> sqr;
    for (std::size_t k = 0; k < members.size(); ++k) {
      tree.radiusSearch((*cloud)[k], eps, found, sqr);
      for (auto j : found) uf.join(k, static_cast<std::size_t>(j));
    }
  }
  std::vector<std::vector<std::size_t>> groups(members.size());
  for (std::size_t k = 0; k < members.size(); ++k) groups[uf.find(k)].push_back(members[k]);
  std::vector<std::vector<std::size_t>> out;
  for (auto& g : groups) {
    if (g.empty()) continue;
    sortByKey(nodes, g);
    out.push_back(std::move(g));
  }
  std::sort(out.begin(), out.end(),
            [&](const auto& a, const auto& b) { return nodes[a[0]].key < nodes[b[0]].key; });
  return out;
}

bool hasConflict(const std::vector<Node>& nodes, const std::vector<std::size_t>& group) {
  std::set<std::size_t> seen;
  for (auto m : group)
    if (!seen.insert(nodes[m].conflict).second) return true;
  return false;
}

/// Splits a group until no two of its nodes conflict, relinking with a shorter distance; past
/// min_eps keeps, per conflict value, the node nearest the group's median.
void split(const std::vector<Node>& nodes, std::vector<std::size_t> group, double eps,
           double min_eps, std::vector<std::vector<std::size_t>>& out, std::size_t& dropped) {
  if (!hasConflict(nodes, group)) {
    out.push_back(std::move(group));
    return;
  }
  const double shorter = eps * 0.7;
  if (shorter >= min_eps) {
    for (auto& g : components(nodes, group, shorter))
      split(nodes, std::move(g), shorter, min_eps, out, dropped);
    return;
  }
  std::vector<double> xs, ys;
  for (auto m : group) xs.push_back(nodes[m].x), ys.push_back(nodes[m].y);
  const double mx = upperMedian(xs), my = upperMedian(ys);
  auto dist = [&](std::size_t m) { return std::hypot(nodes[m].x - mx, nodes[m].y - my); };
  std::vector<std::size_t> order = group;
  std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) { return dist(a) < dist(b); });
  std::set<std::size_t> seen;
  std::vector<std::size_t> kept;
  for (auto m : order) {
    if (seen.insert(nodes[m].conflict).second)
      kept.push_back(m);
    else
      ++dropped;
  }
  sortByKey(nodes, kept);
  out.push_back(std::move(kept));
}

/// Groups `members` into conflict-free components.
std::vector<std::vector<std::size_t>> link(const std::vector<Node>& nodes,
                                           const std::vector<std::size_t>& members, double eps,
                                           double min_eps, std::size_t& dropped) {
  std::vector<std::vector<std::size_t>> out;
  for (auto& g : components(nodes, members, eps))
    split(nodes, std::move(g), eps, min_eps, out, dropped);
  return out;
}

/// Weighted median: the value at position (total weight) / 2 of the expanded sorted list (the
/// upper median of the detections when each cluster's detections share one value).
double weightedMedian(std::vector<std::pair<double, std::size_t>> v) {
  std::sort(v.begin(), v.end());
  std::size_t total = 0;
  for (const auto& e : v) total += e.second;
  std::size_t seen = 0;
  for (const auto& e : v) {
    seen += e.second;
    if (seen > total / 2) return e.first;
  }
  return v.empty() ? 0.0 : v.back().first;
}

}  // namespace

std::size_t clusterStop(const std::vector<const ScanDetections*>& scans,
                        const std::vector<Pose2>& viewpoints, const AssociationConfig& cfg,
                        StopClusters& out, std::vector<std::vector<int>>* cluster_of) {
  if (viewpoints.size() != scans.size())
    throw std::invalid_argument("clusterStop: one viewpoint per scan expected");
  std::vector<Node> items;
  std::vector<std::pair<std::size_t, std::size_t>> where;  // (scan, detection) of each item
  if (cluster_of) cluster_of->assign(scans.size(), {});
  for (std::size_t s = 0; s < scans.size(); ++s) {
    if (scans[s]->stop != scans.front()->stop)
      throw std::invalid_argument("clusterStop: scans of one stop expected");
    if (cluster_of) (*cluster_of)[s].assign(scans[s]->detections.size(), -1);
    for (std::size_t j = 0; j < scans[s]->detections.size(); ++j) {
      const Detection& d = scans[s]->detections[j];
      Node n;
      viewpoints[s].toWorld(d.centre_x_m, d.centre_y_m, n.x, n.y);
      n.conflict = s;
      const double bearing = d.bearing_rad < 0.0 ? d.bearing_rad + 2.0 * kPi : d.bearing_rad;
      n.key = Key{scans[s]->scan_index, scans[s]->stop, bearing, n.x, n.y};
      items.push_back(n);
      where.emplace_back(s, j);
    }
  }
  std::vector<std::size_t> members(items.size());
  std::iota(members.begin(), members.end(), 0);
  std::size_t dropped = 0;
  // At one stop (one pose, only noise), the detections of one object, one per scan.
  for (auto& g : link(items, members, cfg.stop_link_distance_m,
                      std::min(cfg.min_link_distance_m, cfg.stop_link_distance_m), dropped)) {
    StopCluster c;
    c.stop = scans.front()->stop;
    c.strong =
        static_cast<double>(g.size()) >= cfg.min_scan_fraction * static_cast<double>(scans.size());
    std::vector<std::pair<double, std::size_t>> radii;
    for (auto m : g) {
      c.x_m += items[m].x, c.y_m += items[m].y;
      radii.emplace_back(scans[where[m].first]->detections[where[m].second].radius_m, 1);
      if (cluster_of) (*cluster_of)[where[m].first][where[m].second] = static_cast<int>(out.size());
    }
    c.detections = g.size();
    c.x_m /= static_cast<double>(g.size());
    c.y_m /= static_cast<double>(g.size());
    c.radius_m = weightedMedian(std::move(radii));
    c.first = items[g.front()].key;
    out.push_back(c);
  }
  return dropped;
}

double StopLinker::Track::distanceTo(double x, double y) const {
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t q = 0; q < std::min(sightings, recent.size()); ++q)
    d = std::min(d, std::hypot(x - recent[q].first, y - recent[q].second));
  return d;
}

double StopLinker::reach(const Track& t) const {
  if (config_.drift_per_m == 0.0) return config_.link_distance_m;
  return std::min(config_.link_distance_m + config_.drift_per_m * (travel_m_ - t.seen_at_m),
                  std::max(config_.max_link_distance_m, config_.link_distance_m));
}

void StopLinker::moveTo(const Pose2& pose) {
  if (pose_)
    travel_m_ += std::hypot(pose.x_m - pose_->x_m, pose.y_m - pose_->y_m) +
                 1.0 * std::abs(wrapAngle(pose.yaw_rad - pose_->yaw_rad));  // 1 m per radian turned
  pose_ = pose;
}

int TrackIds::of(TrackSerial serial) const {
  const auto it = std::lower_bound(ids.begin(), ids.end(), std::make_pair(serial, 0));
  return it != ids.end() && it->first == serial ? it->second : 0;
}

std::vector<int> landmarkIds(const std::vector<int>& cluster_of,
                             const std::vector<TrackSerial>& track_of, const TrackIds& ids) {
  std::vector<int> out(cluster_of.size(), 0);
  for (std::size_t j = 0; j < out.size(); ++j)
    if (cluster_of[j] >= 0) out[j] = ids.of(track_of.at(static_cast<std::size_t>(cluster_of[j])));
  return out;
}

StopLinker::StopLinker(const AssociationConfig& config, std::size_t stops) : config_(config) {
  config_.validate();
  min_stops_ = std::max<std::size_t>(
      1, std::min<std::size_t>(static_cast<std::size_t>(config_.min_stops), stops));
}

void StopLinker::merge(Track& into, Track& from) {
  // the older sightings first
  for (std::size_t q = 0; q < std::min(from.sightings, from.recent.size()); ++q)
    into.recent[into.sightings++ % into.recent.size()] = from.recent[q];
  into.strong_stops += from.strong_stops;
  into.detections += from.detections;
  into.sum_x += from.sum_x, into.sum_y += from.sum_y;
  into.first = std::min(into.first, from.first);
  into.last_stop = std::max(into.last_stop, from.last_stop);
  into.seen_at_m = std::max(into.seen_at_m, from.seen_at_m);
  for (const auto& r : from.radii.items()) into.radii.offer(r);
  into.aliases.push_back(from.serial);
  into.aliases.insert(into.aliases.end(), from.aliases.begin(), from.aliases.end());
  std::vector<TrackSerial> co;
  std::set_union(into.co_seen.begin(), into.co_seen.end(), from.co_seen.begin(), from.co_seen.end(),
                 std::back_inserter(co));
  into.co_seen = std::move(co);
  for (auto& t : tracks_) {  // who saw `from` close by saw `into`
    auto it = std::lower_bound(t.co_seen.begin(), t.co_seen.end(), from.serial);
    if (it == t.co_seen.end() || *it != from.serial) continue;
    t.co_seen.erase(it);
    if (&t != &into)
      t.co_seen.insert(std::lower_bound(t.co_seen.begin(), t.co_seen.end(), into.serial),
                       into.serial);
  }
  merged_.emplace_back(from.serial, into.serial);
  from.dead = true;
}

std::vector<TrackSerial> StopLinker::add(const StopClusters& clusters,
                                         std::size_t stage1_conflicts) {
  forgotten_.clear();
  merged_.clear();
  totals_.discarded_conflicts += stage1_conflicts;
  totals_.detections += stage1_conflicts;
  if (clusters.empty()) return {};
  StopWork w{clusters, beginStop(clusters), std::vector<TrackSerial>(clusters.size(), 0),
             std::vector<bool>(tracks_.size(), false)};
  // Stage 2: strong clusters continue tracks, or start new ones (in key order).
  assign(w, true, -1.0);
  startTracks(w);
  w.taken.resize(tracks_.size(), true);  // seen strongly at this stop
  recordCoSeen(w);
  mergeSplitTracks(w);
  dropMerged(w);
  // Stage 3: weak clusters join a track not seen strongly here.
  assign(w, false, config_.stop_link_distance_m);
  for (std::size_t k = 0; k < clusters.size(); ++k)
    if (w.serial_of[k] == 0) totals_.discarded_few_stops += clusters[k].detections;
  // Stage 4 (bounded memory).
  forgetStale(w.stop);
  return w.serial_of;
}

/// Checks that the clusters are of one stop, later than the last one; returns the stop.
std::size_t StopLinker::beginStop(const StopClusters& clusters) {
  const std::size_t stop = clusters.front().stop;
  for (const auto& c : clusters) {
    if (c.stop != stop)
      throw std::invalid_argument("StopLinker::add: clusters of one stop expected");
    totals_.detections += c.detections;
  }
  if (started_ && stop <= last_stop_)
    throw std::invalid_argument("StopLinker::add: stops must come in increasing order");
  started_ = true;
  last_stop_ = stop;
  return stop;
}

/// Cluster k joins track t.
void StopLinker::join(StopWork& w, std::size_t k, Track& t) {
  const StopCluster& c = w.clusters[k];
  w.serial_of[k] = t.serial;
  if (c.strong) {
    ++t.strong_stops;
    t.recent[t.sightings++ % t.recent.size()] = {c.x_m, c.y_m};
    t.seen_at_m = travel_m_;
  }
  t.last_stop = w.stop;
  const auto n = static_cast<double>(c.detections);
  t.detections += c.detections;
  t.sum_x += n * c.x_m, t.sum_y += n * c.y_m;
  t.first = std::min(t.first, c.first);
  t.radii.offer({c.radius_m, c.detections});
}

/// Joins the strong (or weak) clusters to tracks: closest (cluster, track) pairs first within
/// reach, `fixed_reach` or, when negative, each track's own reach (stage 2); ties by the
/// cluster's key, then serial (both order-free). Tracks already taken at this stop are skipped.
void StopLinker::assign(StopWork& w, bool strong, double fixed_reach) {
  std::vector<std::tuple<double, DetectionKey, TrackSerial, std::size_t, std::size_t>> pairs;
  for (std::size_t k = 0; k < w.clusters.size(); ++k) {
    if (w.clusters[k].strong != strong) continue;
    for (std::size_t t = 0; t < tracks_.size(); ++t) {
      if (w.taken[t]) continue;
      const double d = tracks_[t].distanceTo(w.clusters[k].x_m, w.clusters[k].y_m);
      if (d <= (fixed_reach < 0.0 ? reach(tracks_[t]) : fixed_reach))
        pairs.emplace_back(d, w.clusters[k].first, tracks_[t].serial, k, t);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  for (const auto& [d, key, serial, k, t] : pairs) {
    if (w.serial_of[k] != 0 || w.taken[t]) continue;
    w.taken[t] = true;
    join(w, k, tracks_[t]);
  }
}

/// Strong clusters that joined no track start one each (in key order).
void StopLinker::startTracks(StopWork& w) {
  for (std::size_t k = 0; k < w.clusters.size(); ++k) {
    if (!w.clusters[k].strong || w.serial_of[k] != 0) continue;
    Track t;
    t.serial = next_serial_++;
    t.first = w.clusters[k].first;
    tracks_.push_back(std::move(t));
    join(w, k, tracks_.back());
  }
}

std::size_t StopLinker::index(TrackSerial serial) const {
  for (std::size_t t = 0; t < tracks_.size(); ++t)
    if (tracks_[t].serial == serial) return t;
  throw std::logic_error("StopLinker: no track " + std::to_string(serial));
}

/// Tracks seen close to each other at this stop are two objects: never merged.
void StopLinker::recordCoSeen(const StopWork& w) {
  const double near = 2.0 * config_.link_distance_m;
  const StopClusters& clusters = w.clusters;
  for (std::size_t a = 0; a < clusters.size(); ++a)
    for (std::size_t b = 0; b < clusters.size(); ++b) {
      if (a == b || w.serial_of[a] == 0 || w.serial_of[b] == 0 ||
          std::hypot(clusters[a].x_m - clusters[b].x_m, clusters[a].y_m - clusters[b].y_m) > near)
        continue;
      auto& co = tracks_[index(w.serial_of[a])].co_seen;
      const auto it = std::lower_bound(co.begin(), co.end(), w.serial_of[b]);
      if (it == co.end() || *it != w.serial_of[b]) co.insert(it, w.serial_of[b]);
    }
}

/// One object found as two tracks: a strong cluster here within reach of a track not seen at
/// this stop, never seen close to the cluster's track, joins them (into the older one).
void StopLinker::mergeSplitTracks(StopWork& w) {
  for (std::size_t k = 0; k < w.clusters.size(); ++k) {
    if (!w.clusters[k].strong) continue;
    for (std::size_t t = 0; t < tracks_.size(); ++t) {
      Track& other = tracks_[t];
      if (w.taken[t] || other.dead) continue;
      if (other.distanceTo(w.clusters[k].x_m, w.clusters[k].y_m) > config_.link_distance_m)
        continue;
      Track& mine = tracks_[index(w.serial_of[k])];
      if (std::binary_search(mine.co_seen.begin(), mine.co_seen.end(), other.serial)) continue;
      Track& into = mine.serial < other.serial ? mine : other;
      Track& from = mine.serial < other.serial ? other : mine;
      merge(into, from);
      for (auto& s : w.serial_of)
        if (s == from.serial) s = into.serial;
      w.taken[index(into.serial)] = true;
    }
  }
}

/// Drops the tracks merged into others.
void StopLinker::dropMerged(StopWork& w) {
  std::size_t kept = 0;
  for (std::size_t t = 0; t < tracks_.size(); ++t) {
    if (tracks_[t].dead) continue;
    if (kept != t) tracks_[kept] = std::move(tracks_[t]), w.taken[kept] = w.taken[t];
    ++kept;
  }
  tracks_.resize(kept);
  w.taken.resize(kept);
}

/// Forgets the tracks left behind before they were seen often enough (bounded memory).
void StopLinker::forgetStale(std::size_t stop) {
  std::size_t w = 0;
  for (std::size_t t = 0; t < tracks_.size(); ++t) {
    Track& tr = tracks_[t];
    const std::size_t unseen = stop - tr.last_stop;
    const bool landmark = tr.strong_stops >= min_stops_;
    const bool stale = landmark ? config_.forget_landmarks_after_stops > 0 &&
                                      unseen > config_.forget_landmarks_after_stops
                                : unseen > config_.forget_after_stops;
    if (stale) {
      forgotten_.push_back(tr.serial);
      forgotten_.insert(forgotten_.end(), tr.aliases.begin(), tr.aliases.end());
      if (!landmark) {
        totals_.discarded_few_stops += tr.detections;
        ++totals_.discarded_components;
      }
      continue;
    }
    if (w != t) tracks_[w] = std::move(tr);
    ++w;
  }
  tracks_.resize(w);
  if (forgotten_.empty()) return;
  std::vector<TrackSerial> gone = forgotten_;
  std::sort(gone.begin(), gone.end());
  for (auto& t : tracks_)
    t.co_seen.erase(std::remove_if(t.co_seen.begin(), t.co_seen.end(),
                                   [&](TrackSerial s) {
                                     return std::binary_search(gone.begin(), gone.end(), s);
                                   }),
                    t.co_seen.end());
}

Association StopLinker::finish(TrackIds& ids) const {
  Association out = totals_;
  std::vector<const Track*> kept;
  for (const auto& t : tracks_) {
    if (t.strong_stops >= min_stops_) {
      kept.push_back(&t);
    } else {
      out.discarded_few_stops += t.detections;
      ++out.discarded_components;
    }
  }
  // Ids by first sighting, then bearing in that scan, then position (all order-free).
  std::sort(kept.begin(), kept.end(),
            [](const Track* a, const Track* b) { return a->first < b->first; });
  ids.ids.clear();
  for (std::size_t rank = 0; rank < kept.size(); ++rank) {
    const Track& t = *kept[rank];
    Landmark l;
    l.id = static_cast<int>(rank + 1);
    l.detections = t.detections;
    l.stops = t.strong_stops;
    l.x_m = t.sum_x / static_cast<double>(t.detections);
    l.y_m = t.sum_y / static_cast<double>(t.detections);
    l.radius_m = weightedMedian(t.radii.items());
    l.first_scan = std::get<0>(t.first);
    out.assigned += l.detections;
    out.landmarks.push_back(l);
    ids.ids.emplace_back(t.serial, l.id);
    for (auto a : t.aliases) ids.ids.emplace_back(a, l.id);
  }
  std::sort(ids.ids.begin(), ids.ids.end());
  return out;
}

Association associate(const std::vector<ScanDetections>& scans,
                      const std::vector<Pose2>& viewpoints, const AssociationConfig& cfg) {
  cfg.validate();
  if (viewpoints.size() != scans.size())
    throw std::invalid_argument("associate: one viewpoint per scan expected");
  std::map<std::size_t, std::vector<std::size_t>> scans_at_stop;
  for (std::size_t s = 0; s < scans.size(); ++s) scans_at_stop[scans[s].stop].push_back(s);
  StopLinker linker(cfg, scans_at_stop.size());
  std::vector<std::vector<int>> cluster_of(scans.size());  // per scan, per detection
  // per scan: its stop's clusters' tracks
  std::vector<std::vector<TrackSerial>> track_of(scans.size());
  for (const auto& [stop, members] : scans_at_stop) {
    std::vector<const ScanDetections*> ptrs;
    std::vector<Pose2> poses;
    for (auto s : members) ptrs.push_back(&scans[s]), poses.push_back(viewpoints[s]);
    StopClusters clusters;
    std::vector<std::vector<int>> of;
    const std::size_t conflicts = clusterStop(ptrs, poses, cfg, clusters, &of);
    linker.moveTo(poses.front());
    const std::vector<TrackSerial> tracks = linker.add(clusters, conflicts);
    for (std::size_t i = 0; i < members.size(); ++i)
      cluster_of[members[i]] = std::move(of[i]), track_of[members[i]] = tracks;
  }
  TrackIds ids;
  Association out = linker.finish(ids);
  out.ids.resize(scans.size());
  for (std::size_t s = 0; s < scans.size(); ++s)
    out.ids[s] = landmarkIds(cluster_of[s], track_of[s], ids);
  return out;
}

}  // namespace lidarcal::detectors
