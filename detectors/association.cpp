#include "detectors/association.hpp"

#include <algorithm>
#include <cmath>
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
  if (!(min_link_distance_m > 0.0 && min_link_distance_m <= link_distance_m))
    fail("min_link_distance_m", "must be in (0, link_distance_m]");
  if (min_stops < 1) fail("min_stops", "must be >= 1");
  if (!(min_scan_fraction >= 0.0 && min_scan_fraction <= 1.0)) fail("min_scan_fraction", "must be in [0, 1]");
}

namespace {

/// A detection in the world frame.
struct Item {
  std::size_t scan = 0, det = 0;  // input scan and detection within it
  std::size_t scan_index = 0, stop = 0;
  double x = 0.0, y = 0.0;        // world position of the centre, metres
  double bearing = 0.0;           // in the sensor frame, [0, 2 pi)
};

/// Order-free key of an item (the input position is not part of it).
auto key(const Item& a) { return std::make_tuple(a.scan_index, a.stop, a.bearing, a.x, a.y); }

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

/// Connected components of the graph "closer than eps" over `members` (indices into items).
/// Members of each component are sorted by key; components by their first member's key.
std::vector<std::vector<std::size_t>> components(const std::vector<Item>& items, const std::vector<std::size_t>& members,
                                                 double eps) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(members.size());
  for (auto m : members) cloud->push_back(pcl::PointXYZ(static_cast<float>(items[m].x), static_cast<float>(items[m].y), 0.0f));
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
    std::sort(g.begin(), g.end(), [&](auto a, auto b) { return key(items[a]) < key(items[b]); });
    out.push_back(std::move(g));
  }
  std::sort(out.begin(), out.end(), [&](const auto& a, const auto& b) { return key(items[a[0]]) < key(items[b[0]]); });
  return out;
}

bool hasConflict(const std::vector<Item>& items, const std::vector<std::size_t>& group) {
  std::set<std::size_t> scans;
  for (auto m : group)
    if (!scans.insert(items[m].scan).second) return true;
  return false;
}

double median(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

/// Splits a component until no scan has two detections in it; past the shortest linking distance
/// keeps, per scan, the detection nearest the component's median.
void split(const std::vector<Item>& items, std::vector<std::size_t> group, double eps, const AssociationConfig& cfg,
           std::vector<std::vector<std::size_t>>& out, std::size_t& dropped) {
  if (!hasConflict(items, group)) {
    out.push_back(std::move(group));
    return;
  }
  const double shorter = eps * 0.7;
  if (shorter >= cfg.min_link_distance_m) {
    for (auto& g : components(items, group, shorter)) split(items, std::move(g), shorter, cfg, out, dropped);
    return;
  }
  std::vector<double> xs, ys;
  for (auto m : group) xs.push_back(items[m].x), ys.push_back(items[m].y);
  const double mx = median(xs), my = median(ys);
  auto dist = [&](std::size_t m) { return std::hypot(items[m].x - mx, items[m].y - my); };
  std::vector<std::size_t> order = group;
  std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) { return dist(a) < dist(b); });
  std::set<std::size_t> scans;
  std::vector<std::size_t> kept;
  for (auto m : order) {
    if (scans.insert(items[m].scan).second)
      kept.push_back(m);
    else
      ++dropped;
  }
  std::sort(kept.begin(), kept.end(), [&](auto a, auto b) { return key(items[a]) < key(items[b]); });
  out.push_back(std::move(kept));
}

}  // namespace

Association associate(const std::vector<ScanDetections>& scans, const std::vector<Pose2>& viewpoints,
                      const AssociationConfig& cfg) {
  cfg.validate();
  if (viewpoints.size() != scans.size()) throw std::invalid_argument("associate: one viewpoint per scan expected");
  Association out;
  out.ids.resize(scans.size());
  std::vector<Item> items;
  std::map<std::size_t, std::size_t> scans_at_stop;
  for (std::size_t s = 0; s < scans.size(); ++s) {
    ++scans_at_stop[scans[s].stop];
    out.ids[s].assign(scans[s].detections.size(), 0);
    for (std::size_t j = 0; j < scans[s].detections.size(); ++j) {
      const Detection& d = scans[s].detections[j];
      Item it;
      it.scan = s, it.det = j, it.scan_index = scans[s].scan_index, it.stop = scans[s].stop;
      viewpoints[s].toWorld(d.centre_x_m, d.centre_y_m, it.x, it.y);
      it.bearing = d.bearing_rad < 0.0 ? d.bearing_rad + 2.0 * kPi : d.bearing_rad;
      items.push_back(it);
    }
  }
  out.detections = items.size();
  const std::size_t min_stops = std::min<std::size_t>(static_cast<std::size_t>(cfg.min_stops), scans_at_stop.size());

  std::vector<std::size_t> everyone(items.size());
  std::iota(everyone.begin(), everyone.end(), 0);
  std::vector<std::vector<std::size_t>> groups;
  for (auto& g : components(items, everyone, cfg.link_distance_m))
    split(items, std::move(g), cfg.link_distance_m, cfg, groups, out.discarded_conflicts);

  struct Candidate {
    Landmark landmark;
    double first_bearing = 0.0;
    const std::vector<std::size_t>* members = nullptr;
  };
  std::vector<Candidate> candidates;
  for (const auto& g : groups) {
    std::map<std::size_t, std::set<std::size_t>> scans_seeing;  // stop -> scans that detected it
    for (auto m : g) scans_seeing[items[m].stop].insert(items[m].scan);
    std::size_t stops = 0;
    for (const auto& [stop, seen] : scans_seeing)
      if (static_cast<double>(seen.size()) >= cfg.min_scan_fraction * static_cast<double>(scans_at_stop[stop])) ++stops;
    if (stops < min_stops) {
      out.discarded_few_stops += g.size();
      ++out.discarded_components;
      continue;
    }
    Candidate c;
    c.members = &g;
    c.landmark.detections = g.size();
    c.landmark.stops = stops;
    for (auto m : g) c.landmark.x_m += items[m].x, c.landmark.y_m += items[m].y;
    c.landmark.x_m /= static_cast<double>(g.size());
    std::vector<double> radii;
    for (auto m : g) radii.push_back(scans[items[m].scan].detections[items[m].det].radius_m);
    c.landmark.radius_m = median(radii);
    c.landmark.y_m /= static_cast<double>(g.size());
    // Members are sorted by key: the first one is the first sighting (smallest bearing among ties).
    c.landmark.first_scan = items[g.front()].scan_index;
    c.first_bearing = items[g.front()].bearing;
    candidates.push_back(c);
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::make_tuple(a.landmark.first_scan, a.first_bearing, a.landmark.x_m, a.landmark.y_m) <
           std::make_tuple(b.landmark.first_scan, b.first_bearing, b.landmark.x_m, b.landmark.y_m);
  });
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    Landmark l = candidates[k].landmark;
    l.id = static_cast<int>(k + 1);
    for (auto m : *candidates[k].members) out.ids[items[m].scan][items[m].det] = l.id;
    out.assigned += l.detections;
    out.landmarks.push_back(l);
  }
  return out;
}

}  // namespace lidarcal::detectors
