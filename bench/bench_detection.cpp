// SPDX-License-Identifier: BSD-3-Clause
// Detection throughput (scans per second) and per-scan accuracy of lidarcal's detector side by
// side with a plain PCL baseline on the same simulated scans, in one run:
//
//   build/bench/bench_detection --benchmark_counters_tabular=true
//
// Baseline: pcl::EuclideanClusterExtraction (tolerance 0.10 m, at least 3 points; the same
// 0.10 m as our gap at range 0) and, on each cluster, pcl::SACSegmentation with SACMODEL_CIRCLE2D
// and PCL's defaults (RANSAC, 50 iterations, optimised coefficients, no radius limits); a cluster
// is a landmark when the circle keeps at least 3 points and its radius lies in [R/2, 2R] (the same
// bounds our detector uses with a known radius). Scans: data/scenes/paper_field.json and
// field_clutter.json, 100 scans each (seed 1). Accuracy (precision, recall, centre, bearing and
// range errors) is per scan, before association, against the simulator's per-beam truth
// (definitions in detectors/evaluation.hpp).

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/console/print.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/sac_segmentation.h>

#include "detectors/evaluation.hpp"
#include "detectors/scan_detector.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/scene_io.hpp"
#include "simulation/simulator.hpp"

namespace {

using namespace lidarcal;
using namespace lidarcal::detectors;

constexpr double kRadius = 0.12;

struct Data {
  Truth truth;
  std::vector<simulation::SimulatedScan> scans;
  std::vector<std::size_t> stop_of_scan;
  std::vector<ScanTruth> scan_truth;
};

const Data& data(const std::string& scene_file) {
  static std::map<std::string, std::unique_ptr<Data>> cache;
  auto& d = cache[scene_file];
  if (d) return *d;
  d = std::make_unique<Data>();
  d->truth.scene = io::readScene(std::string(LIDARCAL_SOURCE_DIR) + "/data/scenes/" + scene_file);
  d->truth.seed = 1;
  d->truth.stops = simulation::planStops(d->truth.scene, 1);
  simulation::SimulatedSequence sequence =
      simulation::simulateSequence(d->truth.scene, d->truth.stops, 1);
  d->scans = std::move(sequence.scans);
  d->stop_of_scan = std::move(sequence.stop_of_scan);
  for (std::size_t i = 0; i < d->scans.size(); ++i)
    d->scan_truth.push_back(makeScanTruth(d->truth, i, d->scans[i].truth, *d->scans[i].scan.cloud));
  return *d;
}

/// The baseline on one scan, reported in our result type so both are scored the same way.
ScanDetections pclBaseline(const pcl::PointCloud<pcl::PointXYZI>& scan) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  pcl::Indices original;  // point of `cloud` -> point of the scan (NaN points removed)
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (std::isfinite(scan[i].x) && std::isfinite(scan[i].y)) {
      cloud->push_back(pcl::PointXYZ(scan[i].x, scan[i].y, 0.0f));
      original.push_back(static_cast<pcl::index_t>(i));
    }
  ScanDetections out;
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  tree->setInputCloud(cloud);
  std::vector<pcl::PointIndices> clusters;
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> ece;
  ece.setClusterTolerance(0.10);
  ece.setMinClusterSize(3);
  ece.setSearchMethod(tree);
  ece.setInputCloud(cloud);
  ece.extract(clusters);
  for (const auto& c : clusters) {
    pcl::PointCloud<pcl::PointXYZ>::Ptr part(new pcl::PointCloud<pcl::PointXYZ>);
    for (auto i : c.indices) part->push_back((*cloud)[static_cast<std::size_t>(i)]);
    pcl::SACSegmentation<pcl::PointXYZ> seg;  // defaults: 50 iterations, optimised coefficients
    seg.setModelType(pcl::SACMODEL_CIRCLE2D);
    seg.setMethodType(pcl::SAC_RANSAC);
    seg.setDistanceThreshold(0.02);
    seg.setInputCloud(part);
    pcl::PointIndices inliers;
    pcl::ModelCoefficients coef;
    seg.segment(inliers, coef);
    if (inliers.indices.size() < 3 || coef.values.size() != 3) continue;
    if (!(coef.values[2] >= kRadius / 2 && coef.values[2] <= 2 * kRadius)) continue;
    Detection d;
    setCentre(d, Circle2{coef.values[0], coef.values[1], coef.values[2]});
    d.free_status = FitStatus::ok;
    d.free_radius_m = coef.values[2];
    for (auto i : inliers.indices)
      d.inliers.push_back(
          original[static_cast<std::size_t>(c.indices[static_cast<std::size_t>(i)])]);
    out.detections.push_back(std::move(d));
  }
  return out;
}

ScanDetections ours(const pcl::PointCloud<pcl::PointXYZI>& scan) {
  DetectionConfig cfg;
  cfg.landmark_radius_m = kRadius;
  return detectScan(scan, cfg);
}

/// Accuracy counters of one detector over all scans (per scan, before association).
void score(benchmark::State& state, const Data& d,
           ScanDetections (*detector)(const pcl::PointCloud<pcl::PointXYZI>&)) {
  std::vector<ScanDetections> all;
  for (const auto& s : d.scans) all.push_back(detector(*s.scan.cloud));
  const DetectionEvaluation ev = evaluateDetections(all, nullptr, d.scan_truth, d.truth);
  double c2 = 0, b2 = 0, r2 = 0, n = 0;
  for (const auto& bin : ev.bins) {
    c2 += double(bin.detections) * bin.centre_rms_m * bin.centre_rms_m;
    b2 += double(bin.detections) * bin.bearing_rms_rad * bin.bearing_rms_rad;
    r2 += double(bin.detections) * bin.range_rms_m * bin.range_rms_m;
    n += double(bin.detections);
  }
  state.counters["precision"] = ev.precision;
  state.counters["recall"] = ev.recall;
  state.counters["false_pos"] = double(ev.false_positives);
  state.counters["bearing_rms_mrad"] = n > 0 ? 1e3 * std::sqrt(b2 / n) : 0.0;
  state.counters["centre_rms_m"] = n > 0 ? std::sqrt(c2 / n) : 0.0;
  // Range to the centre against what the sensor's own bias predicts, f(D - R) + R.
  state.counters["range_rms_m"] = n > 0 ? std::sqrt(r2 / n) : 0.0;
}

void run(benchmark::State& state, const std::string& scene,
         ScanDetections (*detector)(const pcl::PointCloud<pcl::PointXYZI>&)) {
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  const Data& d = data(scene);
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(detector(*d.scans[k].scan.cloud));
    k = (k + 1) % d.scans.size();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));  // items = scans
  score(state, d, detector);
}

void BM_Lidarcal_PaperField(benchmark::State& s) { run(s, "paper_field.json", ours); }
void BM_PclBaseline_PaperField(benchmark::State& s) { run(s, "paper_field.json", pclBaseline); }
void BM_Lidarcal_Clutter(benchmark::State& s) { run(s, "field_clutter.json", ours); }
void BM_PclBaseline_Clutter(benchmark::State& s) { run(s, "field_clutter.json", pclBaseline); }

/// The whole in-process sequence stage (detection + association) on the 100 scans.
void BM_Lidarcal_Sequence_Clutter(benchmark::State& state) {
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  const Data& d = data("field_clutter.json");
  SequenceDetectionConfig cfg;
  cfg.detection.landmark_radius_m = kRadius;
  for (auto _ : state)
    benchmark::DoNotOptimize(detectSequence(
        d.scans.size(), [&](std::size_t i) { return d.scans[i].scan; }, d.stop_of_scan, cfg));
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * d.scans.size()));
}

BENCHMARK(BM_Lidarcal_PaperField);
BENCHMARK(BM_PclBaseline_PaperField);
BENCHMARK(BM_Lidarcal_Clutter);
BENCHMARK(BM_PclBaseline_Clutter);
BENCHMARK(BM_Lidarcal_Sequence_Clutter)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
