#include "io/import_csv.hpp"

#include <cmath>
#include <string_view>

#include "common/errors.hpp"
#include "io/line_reader.hpp"
#include "io/text_fields.hpp"

namespace lidarcal::io {
namespace {

constexpr const char* kRemedy = "see docs/FORMAT.md (CSV import)";
constexpr std::size_t kAbsent = static_cast<std::size_t>(-1);

struct Columns {
  std::size_t scan = kAbsent, x = kAbsent, y = kAbsent, yaw = kAbsent, angle = kAbsent, range = kAbsent;
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
  static const Known kKnown[] = {{"scan", &Columns::scan},         {"x_m", &Columns::x},
                                 {"y_m", &Columns::y},             {"yaw_rad", &Columns::yaw},
                                 {"angle_rad", &Columns::angle},   {"range_m", &Columns::range},
                                 {"intensity", &Columns::intensity}, {"stamp_s", &Columns::stamp}};
  const std::string where = "line " + std::to_string(reader.lineNumber()) + " (header)";
  for (std::size_t i = 0; i < names.size(); ++i)
    for (const Known& k : kKnown)
      if (names[i] == k.name) {
        if (c.*k.slot != kAbsent)
          throw InputError(reader.file().string(), where, "column '" + std::string(k.name) + "' appears twice", kRemedy);
        c.*k.slot = i;
      }
  for (const Known& k : kKnown) {
    const bool optional = k.slot == &Columns::intensity || k.slot == &Columns::stamp;
    if (!optional && c.*k.slot == kAbsent)
      throw InputError(reader.file().string(), where,
                       "no column '" + std::string(k.name) + "'; the header must name scan,x_m,y_m,yaw_rad,angle_rad,range_m",
                       kRemedy);
  }
  return c;
}

}  // namespace

void CsvConfig::validate() const { checkRangeLimits(range_min_m, range_max_m); }

ImportReport readCsvScans(const std::filesystem::path& csv, const CsvConfig& config, const ScanCallback& on_scan) {
  config.validate();
  LineReader reader(csv);
  ImportReport report;
  std::string line;
  std::vector<std::string_view> fields;
  Columns cols;
  bool have_header = false;
  RawScan scan;
  scan.range_min_m = config.range_min_m;
  scan.range_max_m = config.range_max_m;
  long long current = 0;       // scan id of the rows collected in `scan`
  bool collecting = false;     // `scan` holds rows not yet handed on
  std::size_t scan_first_line = 0;

  const auto fail = [&](const std::string& problem) {
    throw InputError(csv.string(), "line " + std::to_string(reader.lineNumber()), problem, kRemedy);
  };
  const auto number = [&](std::size_t col, const char* name) {
    double v = 0.0;
    if (!parseNumber(fields[col], v) || !std::isfinite(v))
      fail(std::string(name) + " is '" + std::string(fields[col]) + "', not a finite number");
    return v;
  };
  // Hands the collected scan on; returns false when the callback asks to stop.
  const auto flush = [&]() {
    collecting = false;
    scan.source_index = report.scans++;
    scan.progress = reader.progress();
    return on_scan(scan);
  };

  bool stopped = false;
  while (!stopped && reader.next(line)) {
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    splitCommas(line, fields);
    if (!have_header) {
      cols = parseHeader(fields, reader);
      have_header = true;
      continue;
    }
    if (fields.size() != cols.count)
      fail("has " + std::to_string(fields.size()) + " values, the header names " + std::to_string(cols.count) + " columns");
    const double id_value = number(cols.scan, "scan");
    if (id_value != std::floor(id_value) || std::abs(id_value) > 9.0e15) fail("scan must be a whole number");
    const long long id = static_cast<long long>(id_value);
    const Pose2 pose{number(cols.x, "x_m"), number(cols.y, "y_m"), wrapAngle(number(cols.yaw, "yaw_rad"))};
    if (collecting && id != current) {
      if (id < current)
        fail("scan " + std::to_string(id) + " follows scan " + std::to_string(current) +
             ": scan numbers must increase and the rows of a scan must be consecutive");
      if (!flush()) {
        stopped = true;
        break;
      }
    }
    if (!collecting) {
      collecting = true;
      current = id;
      scan_first_line = reader.lineNumber();
      scan.pose = pose;
      scan.angles_rad.clear();
      scan.ranges_m.clear();
      scan.intensities.clear();
      scan.stamp_s = cols.stamp != kAbsent ? number(cols.stamp, "stamp_s") : std::numeric_limits<double>::quiet_NaN();
    } else if (std::abs(pose.x_m - scan.pose.x_m) > 1e-9 || std::abs(pose.y_m - scan.pose.y_m) > 1e-9 ||
               std::abs(wrapAngle(pose.yaw_rad - scan.pose.yaw_rad)) > 1e-9) {
      fail("the pose differs from that on line " + std::to_string(scan_first_line) + " of the same scan " +
           std::to_string(id) + ": a scan has one sensor pose");
    }
    scan.angles_rad.push_back(number(cols.angle, "angle_rad"));
    double r = std::numeric_limits<double>::quiet_NaN();
    const std::string_view range_text = fields[cols.range];
    if (!range_text.empty() && !parseNumber(range_text, r))
      fail("range_m is '" + std::string(range_text) + "', not a number (leave it empty or write nan for no return)");
    scan.ranges_m.push_back(static_cast<float>(r));
    if (cols.intensity != kAbsent) scan.intensities.push_back(static_cast<float>(number(cols.intensity, "intensity")));
  }
  if (stopped) report.stopped_early = true;
  else if (collecting) flush();  // the last scan: nothing left to stop
  if (!have_header) throw InputError(csv.string(), "", "is empty: no header line", kRemedy);
  if (report.scans == 0) throw InputError(csv.string(), "", "has a header but no data row", kRemedy);
  report.notes.push_back("VIEWPOINT = the x_m, y_m, yaw_rad columns");
  return report;
}

}  // namespace lidarcal::io
