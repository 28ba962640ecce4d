#include "detectors/association.hpp"

#include <algorithm>
#include <cmath>
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
  if (!(link_distance_m > 0.0) || !std::isfinite(link_distance_m)) fail("link_distance_m", "must be > 0");
  if (!(stop_link_distance_m > 0.0) || !std::isfinite(stop_link_distance_m)) fail("stop_link_distance_m", "must be > 0");
  if (!(min_link_distance_m > 0.0 && min_link_distance_m <= link_distance_m))
    fail("min_link_distance_m", "must be in (0, link_distance_m]");
  if (min_stops < 1) fail("min_stops", "must be >= 1");
  if (!(min_scan_fraction >= 0.0 && min_scan_fraction <= 1.0)) fail("min_scan_fraction", "must be in [0, 1]");
}

namespace {

using Key = DetectionKey;

/// A point to link: a detection (stage 1) or a stop cluster (stage 2).
struct Node {
  double x = 0.0, y = 0.0;    // world position, metres
  std::size_t conflict = 0;   // two nodes with the same value may not share a group (scan, or stop)
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
std::vector<std::vector<std::size_t>> components(const std::vector<Node>& nodes, const std::vector<std::size_t>& members,
                                                 double eps) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(members.size());
  for (auto m : members) cloud->push_back(pcl::PointXYZ(static_cast<float>(nodes[m].x), static_cast<float>(nodes[m].y), 0.0f));
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
  std::sort(out.begin(), out.end(), [&](const auto& a, const auto& b) { return nodes[a[0]].key < nodes[b[0]].key; });
  return out;
}

bool hasConflict(const std::vector<Node>& nodes, const std::vector<std::size_t>& group) {
  std::set<std::size_t> seen;
  for (auto m : group)
    if (!seen.insert(nodes[m].conflict).second) return true;
  return false;
}

double median(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

/// Splits a group until no two of its nodes conflict, relinking with a shorter distance; past
/// min_eps keeps, per conflict value, the node nearest the group's median.
void split(const std::vector<Node>& nodes, std::vector<std::size_t> group, double eps, double min_eps,
           std::vector<std::vector<std::size_t>>& out, std::size_t& dropped) {
  if (!hasConflict(nodes, group)) {
    out.push_back(std::move(group));
    return;
  }
  const double shorter = eps * 0.7;
  if (shorter >= min_eps) {
    for (auto& g : components(nodes, group, shorter)) split(nodes, std::move(g), shorter, min_eps, out, dropped);
    return;
  }
  std::vector<double> xs, ys;
  for (auto m : group) xs.push_back(nodes[m].x), ys.push_back(nodes[m].y);
  const double mx = median(xs), my = median(ys);
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
std::vector<std::vector<std::size_t>> link(const std::vector<Node>& nodes, const std::vector<std::size_t>& members,
                                           double eps, double min_eps, std::size_t& dropped) {
  std::vector<std::vector<std::size_t>> out;
  for (auto& g : components(nodes, members, eps)) split(nodes, std::move(g), eps, min_eps, out, dropped);
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

std::size_t clusterStop(const std::vector<const ScanDetections*>& scans, const std::vector<Pose2>& viewpoints,
                        const AssociationConfig& cfg, StopClusters& out,
                        std::vector<std::vector<int>>* cluster_of) {
  if (viewpoints.size() != scans.size()) throw std::invalid_argument("clusterStop: one viewpoint per scan expected");
  std::vector<Node> items;
  std::vector<std::pair<std::size_t, std::size_t>> where;  // (scan, detection) of each item
  if (cluster_of) cluster_of->assign(scans.size(), {});
  for (std::size_t s = 0; s < scans.size(); ++s) {
    if (scans[s]->stop != scans.front()->stop) throw std::invalid_argument("clusterStop: scans of one stop expected");
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
  for (auto& g : link(items, members, cfg.stop_link_distance_m, std::min(cfg.min_link_distance_m, cfg.stop_link_distance_m),
                      dropped)) {
    StopCluster c;
    c.stop = scans.front()->stop;
    c.strong = static_cast<double>(g.size()) >= cfg.min_scan_fraction * static_cast<double>(scans.size());
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

std::vector<int> landmarkIds(const std::vector<int>& cluster_of, const std::vector<int>& landmark_of, std::size_t first) {
  std::vector<int> ids(cluster_of.size(), 0);
  for (std::size_t j = 0; j < ids.size(); ++j)
    if (cluster_of[j] >= 0) ids[j] = landmark_of.at(first + static_cast<std::size_t>(cluster_of[j]));
  return ids;
}

Association linkStopClusters(const StopClusters& clusters, std::size_t stops, std::size_t stage1_conflicts,
                             const AssociationConfig& cfg, std::vector<int>& landmark_of) {
  cfg.validate();
  Association out;
  out.discarded_conflicts = stage1_conflicts;
  out.detections = stage1_conflicts;
  for (const auto& c : clusters) out.detections += c.detections;
  landmark_of.assign(clusters.size(), 0);
  const std::size_t min_stops = std::min<std::size_t>(static_cast<std::size_t>(cfg.min_stops), stops);
  std::vector<Node> cnodes;
  std::vector<std::size_t> strong;
  cnodes.reserve(clusters.size());
  for (std::size_t k = 0; k < clusters.size(); ++k) {
    cnodes.push_back(Node{clusters[k].x_m, clusters[k].y_m, clusters[k].stop, clusters[k].first});
    if (clusters[k].strong) strong.push_back(k);
  }

  // Stage 2: strong stop clusters linked across stops, one per stop in a landmark.
  struct Candidate {
    std::vector<std::size_t> clusters;  // indices into `clusters`
    Key first;
  };
  std::vector<Candidate> candidates;
  std::vector<int> candidate_of(clusters.size(), -1);
  for (auto& g : link(cnodes, strong, cfg.link_distance_m, cfg.min_link_distance_m, out.discarded_conflicts)) {
    if (g.size() < min_stops) {
      for (auto k : g) out.discarded_few_stops += clusters[k].detections;
      ++out.discarded_components;
      continue;
    }
    for (auto k : g) candidate_of[k] = static_cast<int>(candidates.size());
    candidates.push_back(Candidate{std::move(g), Key{}});
  }

  // Stage 3: a weak stop cluster (a landmark found in few scans of a stop) joins the landmark
  // whose strong cluster at the nearest stop (by index) lies within stop_link_distance_m, if
  // that landmark has nothing else at this stop.
  std::vector<std::tuple<double, Key, std::size_t, std::size_t>> offers;  // distance, key, cluster, candidate
  for (std::size_t k = 0; k < clusters.size(); ++k) {
    if (clusters[k].strong) continue;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      // Where the landmark appears at the nearest stops (by stop index: stops follow the path).
      std::size_t gap = std::numeric_limits<std::size_t>::max();
      for (auto q : candidates[c].clusters)
        gap = std::min(gap, clusters[q].stop > clusters[k].stop ? clusters[q].stop - clusters[k].stop
                                                                 : clusters[k].stop - clusters[q].stop);
      double best = std::numeric_limits<double>::infinity();
      for (auto q : candidates[c].clusters) {
        const std::size_t g = clusters[q].stop > clusters[k].stop ? clusters[q].stop - clusters[k].stop
                                                                   : clusters[k].stop - clusters[q].stop;
        if (g == gap) best = std::min(best, std::hypot(cnodes[q].x - cnodes[k].x, cnodes[q].y - cnodes[k].y));
      }
      if (best <= cfg.stop_link_distance_m) offers.emplace_back(best, cnodes[k].key, k, c);
    }
  }
  std::sort(offers.begin(), offers.end());
  std::set<std::pair<std::size_t, std::size_t>> taken_stop;  // (candidate, stop)
  for (std::size_t c = 0; c < candidates.size(); ++c)
    for (auto q : candidates[c].clusters) taken_stop.emplace(c, clusters[q].stop);
  for (const auto& [dist, key, k, c] : offers) {
    if (candidate_of[k] >= 0 || taken_stop.count({c, clusters[k].stop})) continue;
    candidate_of[k] = static_cast<int>(c);
    taken_stop.emplace(c, clusters[k].stop);
    candidates[c].clusters.push_back(k);
  }
  for (std::size_t k = 0; k < clusters.size(); ++k)
    if (!clusters[k].strong && candidate_of[k] < 0) out.discarded_few_stops += clusters[k].detections;

  // Ids by first sighting, then bearing in that scan, then position (all order-free).
  std::vector<Landmark> found;
  for (auto& c : candidates) {
    Landmark l;
    std::vector<std::pair<double, std::size_t>> radii;
    c.first = cnodes[c.clusters.front()].key;
    for (auto k : c.clusters) {
      if (clusters[k].strong) ++l.stops;
      c.first = std::min(c.first, cnodes[k].key);
      const auto n = static_cast<double>(clusters[k].detections);
      l.detections += clusters[k].detections;
      l.x_m += n * clusters[k].x_m, l.y_m += n * clusters[k].y_m;
      radii.emplace_back(clusters[k].radius_m, clusters[k].detections);
    }
    l.x_m /= static_cast<double>(l.detections);
    l.y_m /= static_cast<double>(l.detections);
    l.radius_m = weightedMedian(std::move(radii));
    l.first_scan = std::get<0>(c.first);
    found.push_back(l);
  }
  std::vector<std::size_t> order(candidates.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return candidates[a].first < candidates[b].first; });
  for (std::size_t rank = 0; rank < order.size(); ++rank) {
    Landmark l = found[order[rank]];
    l.id = static_cast<int>(rank + 1);
    for (auto k : candidates[order[rank]].clusters) landmark_of[k] = l.id;
    out.assigned += l.detections;
    out.landmarks.push_back(l);
  }
  return out;
}

Association associate(const std::vector<ScanDetections>& scans, const std::vector<Pose2>& viewpoints,
                      const AssociationConfig& cfg) {
  cfg.validate();
  if (viewpoints.size() != scans.size()) throw std::invalid_argument("associate: one viewpoint per scan expected");
  std::map<std::size_t, std::vector<std::size_t>> scans_at_stop;
  for (std::size_t s = 0; s < scans.size(); ++s) scans_at_stop[scans[s].stop].push_back(s);
  StopClusters clusters;
  std::vector<std::vector<std::vector<int>>> cluster_of;  // per stop, per scan of the stop, per detection
  std::size_t conflicts = 0;
  for (const auto& [stop, members] : scans_at_stop) {
    std::vector<const ScanDetections*> ptrs;
    std::vector<Pose2> poses;
    for (auto s : members) ptrs.push_back(&scans[s]), poses.push_back(viewpoints[s]);
    cluster_of.emplace_back();
    conflicts += clusterStop(ptrs, poses, cfg, clusters, &cluster_of.back());
  }
  std::vector<int> landmark_of;
  Association out = linkStopClusters(clusters, scans_at_stop.size(), conflicts, cfg, landmark_of);
  out.ids.resize(scans.size());
  std::size_t k = 0;
  for (const auto& [stop, members] : scans_at_stop) {
    for (std::size_t i = 0; i < members.size(); ++i) out.ids[members[i]] = landmarkIds(cluster_of[k][i], landmark_of);
    ++k;
  }
  return out;
}

}  // namespace lidarcal::detectors
