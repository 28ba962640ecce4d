// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/detection_log.hpp"

#include <cerrno>
#include <cstring>
#include <string>

#include "common/errors.hpp"

namespace lidarcal::detectors {

namespace {

/// A detection's fixed-size part, written as one block (read back by the same build).
struct DetectionRecord {
  double centre_x_m, centre_y_m, radius_m, bearing_rad, range_m, rms_m;
  double free_centre_x_m, free_centre_y_m, free_radius_m, free_rms_m, free_radius_stddev_m;
  std::uint64_t cluster_points, track, inliers;
  std::int32_t free_status;
  std::uint8_t radius_fixed;
};

struct ScanRecord {
  std::uint64_t scan_index, stop, returns, detections, points_print;
};

[[noreturn]] void fail(const char* what) {
  throw InputError("temporary file of the detections", "",
                   std::string(what) + ": " + std::strerror(errno),
                   "free space where TMPDIR points (default /tmp) and run again");
}

bool put(std::FILE* f, const void* data, std::size_t bytes) {
  return bytes == 0 || std::fwrite(data, 1, bytes, f) == bytes;
}

bool get(std::FILE* f, void* data, std::size_t bytes, bool end_allowed = false) {
  if (bytes == 0) return true;
  const std::size_t n = std::fread(data, 1, bytes, f);
  if (n == bytes) return true;
  if (n == 0 && end_allowed && std::feof(f)) return false;
  fail("cannot read back");
}

}  // namespace

std::shared_ptr<DetectionLog> DetectionLog::create() {
  std::FILE* f = std::tmpfile();
  if (!f) return nullptr;
  return std::shared_ptr<DetectionLog>(new DetectionLog(f));
}

DetectionLog::~DetectionLog() { std::fclose(file_); }

bool DetectionLog::append(const ScanDetections& scan, const std::vector<TrackSerial>& tracks,
                          std::uint64_t points_print) {
  const ScanRecord s{scan.scan_index, scan.stop, scan.returns, scan.detections.size(),
                     points_print};
  bool ok = put(file_, &s, sizeof s);
  for (std::size_t j = 0; ok && j < scan.detections.size(); ++j) {
    const Detection& d = scan.detections[j];
    DetectionRecord r{};
    r.centre_x_m = d.centre_x_m, r.centre_y_m = d.centre_y_m, r.radius_m = d.radius_m;
    r.bearing_rad = d.bearing_rad, r.range_m = d.range_m, r.rms_m = d.rms_m;
    r.free_centre_x_m = d.free_centre_x_m, r.free_centre_y_m = d.free_centre_y_m,
    r.free_radius_m = d.free_radius_m;
    r.free_rms_m = d.free_rms_m, r.free_radius_stddev_m = d.free_radius_stddev_m;
    r.cluster_points = d.cluster_points, r.track = tracks.at(j), r.inliers = d.inliers.size();
    r.free_status = static_cast<std::int32_t>(d.free_status);
    r.radius_fixed = d.radius_fixed ? 1 : 0;
    ok = put(file_, &r, sizeof r) &&
         put(file_, d.inliers.data(), d.inliers.size() * sizeof(d.inliers[0]));
  }
  return ok;
}

bool DetectionLog::finish() { return std::fflush(file_) == 0; }

void DetectionLog::rewind() { std::rewind(file_); }

bool DetectionLog::next(ScanDetections& scan, std::vector<TrackSerial>& tracks,
                        std::uint64_t& points_print) {
  ScanRecord s{};
  if (!get(file_, &s, sizeof s, true)) return false;
  scan = ScanDetections{};
  scan.scan_index = s.scan_index, scan.stop = s.stop, scan.returns = s.returns;
  points_print = s.points_print;
  scan.detections.resize(s.detections);
  tracks.assign(s.detections, 0);
  for (std::size_t j = 0; j < s.detections; ++j) {
    DetectionRecord r{};
    get(file_, &r, sizeof r);
    Detection& d = scan.detections[j];
    d.centre_x_m = r.centre_x_m, d.centre_y_m = r.centre_y_m, d.radius_m = r.radius_m;
    d.bearing_rad = r.bearing_rad, d.range_m = r.range_m, d.rms_m = r.rms_m;
    d.free_centre_x_m = r.free_centre_x_m, d.free_centre_y_m = r.free_centre_y_m,
    d.free_radius_m = r.free_radius_m;
    d.free_rms_m = r.free_rms_m, d.free_radius_stddev_m = r.free_radius_stddev_m;
    d.cluster_points = r.cluster_points;
    d.free_status = static_cast<FitStatus>(r.free_status);
    d.radius_fixed = r.radius_fixed != 0;
    tracks[j] = r.track;
    d.inliers.resize(r.inliers);
    get(file_, d.inliers.data(), d.inliers.size() * sizeof(d.inliers[0]));
  }
  return true;
}

std::uint64_t pointsPrint(const pcl::PointCloud<pcl::PointXYZI>& cloud) {
  // FNV-1a over 32-bit words (the count, then x, y, z of every point).
  std::uint64_t h = 0xcbf29ce484222325ull;
  auto mix = [&h](std::uint32_t word) { h = (h ^ word) * 0x100000001b3ull; };
  auto bits = [](float v) {
    std::uint32_t w = 0;
    std::memcpy(&w, &v, sizeof w);
    return w;
  };
  mix(static_cast<std::uint32_t>(cloud.size()));
  for (const auto& p : cloud) mix(bits(p.x)), mix(bits(p.y)), mix(bits(p.z));
  return h;
}

}  // namespace lidarcal::detectors
