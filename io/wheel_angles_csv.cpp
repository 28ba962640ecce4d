// SPDX-License-Identifier: BSD-3-Clause
#include "io/wheel_angles_csv.hpp"

#include <cstdio>
#include <set>

#include "common/errors.hpp"
#include "common/number_text.hpp"
#include "io/atomic_file.hpp"
#include "io/csv_row.hpp"

namespace lidarcal::io {
namespace {

constexpr const char* kHeader = "file,left_wheel_rad,right_wheel_rad";
constexpr const char* kRemedy =
    "one row per scan in time order: the scan's file name and each wheel's cumulative angle in "
    "radians (encoder ticks times 2 pi over ticks per turn); see docs/FORMAT.md";

}  // namespace

const char* wheelAnglesCsvHeader() { return kHeader; }

std::vector<WheelAngleRow> readWheelAnglesCsv(const std::filesystem::path& file) {
  CsvReader csv(file, kRemedy);
  csv.expectHeader(kHeader);
  std::vector<WheelAngleRow> rows;
  std::set<std::string> seen;
  while (csv.next(3)) {
    WheelAngleRow row{csv.text(0), csv.number(1, "left_wheel_rad"),
                      csv.number(2, "right_wheel_rad")};
    if (row.file.empty()) csv.fail("file", "is empty");
    if (!seen.insert(row.file).second) csv.fail("file", "`" + row.file + "` appears twice");
    rows.push_back(std::move(row));
  }
  if (rows.size() < 2)
    throw InputError(file.string(), "", "needs at least two scans (one wheel step)", kRemedy);
  return rows;
}

void writeWheelAnglesCsv(const std::filesystem::path& file,
                         const std::vector<WheelAngleRow>& rows) {
  std::string text = std::string(kHeader) + "\n";
  for (const WheelAngleRow& r : rows)
    text += r.file + formatted(",%.9g,%.9g\n", r.left_rad, r.right_rad);
  writeTextAtomically(file, text);
}

}  // namespace lidarcal::io
