#pragma once
// A scan sequence: a directory of .pcd files in lexicographic order, grouped into stops by
// their VIEWPOINT, with optional metadata in sequence.json (docs/FORMAT.md).
// Opening a sequence reads headers only; scans are loaded one at a time with readScan().

#include <cstdint>
#include <filesystem>
#include <iterator>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/pose2.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::io {

/// Optional metadata of a sequence (sequence.json). Ground truth never lives here.
struct SequenceMeta {
  std::optional<std::string> sensor_name;       ///< free text, e.g. "RPLIDAR A2"
  std::optional<double> landmark_radius_m;      ///< common radius of the landmarks, when known
  std::optional<double> range_min_m;            ///< smallest range the sensor reports
  std::optional<double> range_max_m;            ///< largest range the sensor reports
  std::optional<int> beams;                     ///< beams per scan
};

/// Scan indices first, first + 1, ..., first + size - 1 (a stop's scans are consecutive).
class ScanRange {
 public:
  class iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = std::size_t;
    using difference_type = std::ptrdiff_t;
    using pointer = const std::size_t*;
    using reference = std::size_t;
    iterator() = default;
    explicit iterator(std::size_t i) : i_(i) {}
    std::size_t operator*() const { return i_; }
    iterator& operator++() { ++i_; return *this; }
    iterator operator++(int) { iterator t = *this; ++i_; return t; }
    bool operator==(const iterator& o) const { return i_ == o.i_; }
    bool operator!=(const iterator& o) const { return i_ != o.i_; }
   private:
    std::size_t i_ = 0;
  };
  ScanRange() = default;
  ScanRange(std::size_t first, std::size_t size) : first_(first), size_(size) {}
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  std::size_t front() const { return first_; }
  std::size_t back() const { return first_ + size_ - 1; }
  std::size_t operator[](std::size_t k) const { return first_ + k; }
  iterator begin() const { return iterator(first_); }
  iterator end() const { return iterator(first_ + size_); }
  void grow() { ++size_; }  ///< takes in the next scan
 private:
  std::size_t first_ = 0, size_ = 0;
};

/// Consecutive scans taken at one commanded pose.
struct Stop {
  Pose2 commanded;   ///< VIEWPOINT of the stop's first scan
  ScanRange scans;   ///< indices into Sequence::scans, in file order
};

/// The scan headers of a sequence, stored compactly: the file names in one buffer, the
/// viewpoint, point count and flags per scan (about 50 bytes per scan, so that a sequence of
/// 100,000 scans costs 5 MB, not the 20 MB of a vector of headers). Elements are ScanHeader
/// values made on access; every path shares one directory.
class ScanList {
 public:
  class iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = ScanHeader;
    using difference_type = std::ptrdiff_t;
    using pointer = const ScanHeader*;
    using reference = ScanHeader;
    iterator() = default;
    iterator(const ScanList* list, std::size_t i) : list_(list), i_(i) {}
    ScanHeader operator*() const { return (*list_)[i_]; }
    iterator& operator++() { ++i_; return *this; }
    iterator operator++(int) { iterator t = *this; ++i_; return t; }
    bool operator==(const iterator& o) const { return i_ == o.i_; }
    bool operator!=(const iterator& o) const { return i_ != o.i_; }
   private:
    const ScanList* list_ = nullptr;
    std::size_t i_ = 0;
  };
  std::size_t size() const { return name_end_.size(); }
  bool empty() const { return name_end_.empty(); }
  ScanHeader operator[](std::size_t i) const;
  ScanHeader at(std::size_t i) const;  ///< throws std::out_of_range
  std::string path(std::size_t i) const;  ///< the path of scan i (throws std::out_of_range)
  ScanHeader front() const { return at(0); }
  ScanHeader back() const { return at(size() - 1); }
  iterator begin() const { return iterator(this, 0); }
  iterator end() const { return iterator(this, size()); }
  ScanList() = default;
  /// Files `names` in the directory `dir` (with its trailing separator). Every header must then
  /// be set (setHeader) before any is read; the names can be dropped in between.
  ScanList(std::string dir, const std::vector<std::string>& names);
  /// Header of scan i (its path must be the directory + the name given for i).
  void setHeader(std::size_t i, const ScanHeader& header);
  /// Appends a header; its path must be in the directory of the first one.
  void push_back(const ScanHeader& header);

 private:
  std::string dir_;                       // the first path without its file name
  std::string names_;                     // file names, back to back
  std::vector<std::uint64_t> name_end_;   // end of each name in names_
  std::vector<Pose2> viewpoints_;
  std::vector<std::uint64_t> points_;
  std::vector<std::uint8_t> flags_;       // has_intensity 1, has_label 2, binary 4
};

/// Tolerances for "same VIEWPOINT" (docs/FORMAT.md: 1 mm and 0.01 degree).
struct StopTolerance {
  double position_m = 1e-3;               ///< max distance between viewpoints of one stop
  double yaw_rad = 0.01 * 3.14159265358979323846 / 180.0;  ///< max heading difference
};

struct Sequence {
  std::filesystem::path dir;          ///< the sequence directory
  ScanList scans;                     ///< one per .pcd file, lexicographic order
  std::vector<Stop> stops;            ///< consecutive scans with the same VIEWPOINT
  std::vector<std::size_t> stop_of_scan;  ///< stop index of each scan
  SequenceMeta meta;                  ///< sequence.json, when present
};

/// Groups consecutive viewpoints into stops.
std::vector<Stop> groupStops(const std::vector<Pose2>& viewpoints, const StopTolerance& tol = {});

/// Lists and checks a sequence directory (headers and sequence.json only). Throws InputError
/// when the directory is missing, holds no .pcd file, a header is bad, a scan file ends in
/// `.PCD` (any case but `.pcd`), two names carry one scan number (`scan_1.pcd`, `scan_0001.pcd`)
/// or numbers without zero padding would be read out of order (`scan_10.pcd` before
/// `scan_2.pcd`), or a scan's point count differs from sequence.json `beams`.
Sequence openSequence(const std::filesystem::path& dir, const StopTolerance& tol = {});

/// Fewest and most points in a scan of the sequence (equal when every scan has one beam count).
std::pair<std::size_t, std::size_t> pointCountRange(const Sequence& seq);

/// Reads sequence.json (throws InputError on malformed content).
SequenceMeta readSequenceMeta(const std::filesystem::path& file);
/// Writes sequence.json atomically; absent fields are omitted.
void writeSequenceMeta(const std::filesystem::path& file, const SequenceMeta& meta);

/// Name of scan file `index` in a sequence written by lidarcal: scan_000000.pcd, ...
std::string scanFileName(std::size_t index);

}  // namespace lidarcal::io
