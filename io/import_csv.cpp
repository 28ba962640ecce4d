// SPDX-License-Identifier: BSD-3-Clause
#include "io/import_csv.hpp"

#include <cmath>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "common/errors.hpp"
#include "io/line_reader.hpp"
#include "io/text_fields.hpp"

namespace lidarcal::io {
namespace {

constexpr const char* kRemedy = "see docs/FORMAT.md (CSV import)";
constexpr std::size_t kAbsent = static_cast<std::size_t>(-1);

struct Columns {
  std::size_t scan = kAbsent, x = kAbsent, y = kAbsent, yaw = kAbsent, angle = kAbsent,
              range = kAbsent;
  std::size_t intensity = kAbsent, stamp = kAbsent;
  std::size_t count = 0;  // fields in the header
};

Columns parseHeader(const std::vector<std::string_view>& names, const LineReader& reader) {
  Columns c;
  c.count = names.size();
  struct Known {
    const char* name;
    std::size_t Columns::*slot;
  };
  static const Known kKnown[] = {{"scan", &Columns::scan},
                                 {"x_m", &Columns::x},
                                 {"y_m", &Columns::y},
                                 {"yaw_rad", &Columns::yaw},
                                 {"angle_rad", &Columns::angle},
                                 {"range_m", &Columns::range},
                                 {"intensity", &Columns::intensity},
                                 {"stamp_s", &Columns::stamp}};
  const std::string where = "line " + std::to_string(reader.lineNumber()) + " (header)";
  for (std::size_t i = 0; i < names.size(); ++i)
    for (const Known& k : kKnown)
      if (names[i] == k.name) {
        if (c.*k.slot != kAbsent)
          throw InputError(reader.file().string(), where,
                           "column '" + std::string(k.name) + "' appears twice", kRemedy);
        c.*k.slot = i;
      }
  for (const Known& k : kKnown) {
    const bool optional = k.slot == &Columns::intensity || k.slot == &Columns::stamp;
    if (!optional && c.*k.slot == kAbsent)
      throw InputError(reader.file().string(), where,
                       "no column '" + std::string(k.name) +
                           "'; the header must name scan,x_m,y_m,yaw_rad,angle_rad,range_m",
                       kRemedy);
  }
  return c;
}

/// The rows of a CSV file grouped into scans (consecutive rows of one scan id), each handed on
/// when the next scan begins; throws InputError naming the line at fault.
class CsvScanReader {
 public:
  CsvScanReader(const std::filesystem::path& csv, const CsvConfig& config,
                const ScanCallback& on_scan)
      : csv_(csv), on_scan_(on_scan), reader_(csv) {
    scan_.range_min_m = config.range_min_m;
    scan_.range_max_m = config.range_max_m;
  }

  ImportReport run() {
    bool stopped = false;
    while (!stopped && reader_.next(line_)) {
      const std::size_t first = line_.find_first_not_of(" \t");
      if (first == std::string::npos || line_[first] == '#') continue;
      splitCommas(line_, fields_);
      if (!have_header_) {
        cols_ = parseHeader(fields_, reader_);
        have_header_ = true;
        continue;
      }
      stopped = !addRow();
    }
    if (stopped)
      report_.stopped_early = true;
    else if (collecting_)
      flush();  // the last scan: nothing left to stop
    if (!have_header_) throw InputError(csv_.string(), "", "is empty: no header line", kRemedy);
    if (report_.scans == 0)
      throw InputError(csv_.string(), "", "has a header but no data row", kRemedy);
    report_.notes.push_back("VIEWPOINT = the x_m, y_m, yaw_rad columns");
    return report_;
  }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw InputError(csv_.string(), "line " + std::to_string(reader_.lineNumber()), problem,
                     kRemedy);
  }

  double number(std::size_t col, const char* name) const {
    double v = 0.0;
    if (!parseNumber(fields_[col], v) || !std::isfinite(v))
      fail(std::string(name) + " is '" + std::string(fields_[col]) + "', not a finite number");
    return v;
  }

  /// Hands the collected scan on; returns false when the callback asks to stop.
  bool flush() {
    collecting_ = false;
    scan_.source_index = report_.scans++;
    scan_.progress = reader_.progress();
    return on_scan_(scan_);
  }

  /// One data row into the scan (the previous scan handed on when this one begins); false when
  /// the callback asked to stop.
  bool addRow() {
    if (fields_.size() != cols_.count)
      fail("has " + std::to_string(fields_.size()) + " values, the header names " +
           std::to_string(cols_.count) + " columns");
    const double id_value = number(cols_.scan, "scan");
    if (id_value != std::floor(id_value) || std::abs(id_value) > 9.0e15)
      fail("scan must be a whole number");
    const long long id = static_cast<long long>(id_value);
    const Pose2 pose{number(cols_.x, "x_m"), number(cols_.y, "y_m"),
                     wrapAngle(number(cols_.yaw, "yaw_rad"))};
    if (collecting_ && id != current_) {
      if (id < current_)
        fail("scan " + std::to_string(id) + " follows scan " + std::to_string(current_) +
             ": scan numbers must increase and the rows of a scan must be consecutive");
      if (!flush()) return false;
    }
    if (!collecting_) {
      startScan(id, pose);
    } else if (std::abs(pose.x_m - scan_.pose.x_m) > 1e-9 ||
               std::abs(pose.y_m - scan_.pose.y_m) > 1e-9 ||
               std::abs(wrapAngle(pose.yaw_rad - scan_.pose.yaw_rad)) > 1e-9) {
      fail("the pose differs from that on line " + std::to_string(scan_first_line_) +
           " of the same scan " + std::to_string(id) + ": a scan has one sensor pose");
    }
    addBeam();
    return true;
  }

  void startScan(long long id, const Pose2& pose) {
    collecting_ = true;
    current_ = id;
    scan_first_line_ = reader_.lineNumber();
    scan_.pose = pose;
    scan_.angles_rad.clear();
    scan_.ranges_m.clear();
    scan_.intensities.clear();
    scan_.stamp_s = cols_.stamp != kAbsent ? number(cols_.stamp, "stamp_s")
                                           : std::numeric_limits<double>::quiet_NaN();
  }

  /// The row's beam: angle, range (empty or nan: no return) and intensity when there is a column.
  void addBeam() {
    scan_.angles_rad.push_back(number(cols_.angle, "angle_rad"));
    double r = std::numeric_limits<double>::quiet_NaN();
    const std::string_view range_text = fields_[cols_.range];
    if (!range_text.empty() && !parseNumber(range_text, r))
      fail("range_m is '" + std::string(range_text) +
           "', not a number (leave it empty or write nan for no return)");
    scan_.ranges_m.push_back(static_cast<float>(r));
    if (cols_.intensity != kAbsent)
      scan_.intensities.push_back(static_cast<float>(number(cols_.intensity, "intensity")));
  }

  const std::filesystem::path& csv_;
  const ScanCallback& on_scan_;
  LineReader reader_;
  ImportReport report_;
  std::string line_;
  std::vector<std::string_view> fields_;
  Columns cols_;
  bool have_header_ = false;
  RawScan scan_;
  long long current_ = 0;            ///< scan id of the rows collected in scan_
  bool collecting_ = false;          ///< scan_ holds rows not yet handed on
  std::size_t scan_first_line_ = 0;  ///< line of the collected scan's first row
};

}  // namespace

void CsvConfig::validate() const { checkRangeLimits(range_min_m, range_max_m); }

ImportReport readCsvScans(const std::filesystem::path& csv, const CsvConfig& config,
                          const ScanCallback& on_scan) {
  config.validate();
  return CsvScanReader(csv, config, on_scan).run();
}

}  // namespace lidarcal::io
