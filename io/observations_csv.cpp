// SPDX-License-Identifier: BSD-3-Clause
#include "io/observations_csv.hpp"

#include <cstdio>
#include <limits>
#include <map>
#include <string>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/csv_row.hpp"

namespace lidarcal::io {
namespace {

constexpr const char* kRemedy = "see docs/FORMAT.md, section observations.csv and odometry.csv";

int checkedIndex(const CsvReader& csv, std::size_t column, const char* name, long long lowest) {
  const long long v = csv.integer(column, name);
  if (v < lowest) {
    if (lowest == std::numeric_limits<int>::min()) csv.fail(name, "is too small");
    csv.fail(name, "must be >= " + std::to_string(lowest));
  }
  if (v > std::numeric_limits<int>::max()) csv.fail(name, "is too large");
  return static_cast<int>(v);
}

/// Replaces each row's `field` by the index of its value among the values sorted ascending
/// (0..N-1) and returns those values. With `keep_unknown`, -1 (unknown association) stays -1.
std::vector<int> relabel(std::vector<Observation>& rows, int Observation::*field,
                         bool keep_unknown) {
  std::map<int, int> index;
  for (const auto& o : rows)
    if (!(keep_unknown && o.*field == -1)) index.emplace(o.*field, 0);
  std::vector<int> labels;
  for (auto& [label, i] : index) {
    i = static_cast<int>(labels.size());
    labels.push_back(label);
  }
  for (auto& o : rows)
    if (!(keep_unknown && o.*field == -1)) o.*field = index[o.*field];
  return labels;
}

}  // namespace

std::vector<Observation> readObservations(const std::filesystem::path& file,
                                          std::vector<int>* sensor_labels,
                                          std::vector<int>* landmark_labels) {
  CsvReader csv(file, kRemedy);
  csv.expectHeader(kObservationsHeader);
  constexpr long long kAnyInt = std::numeric_limits<int>::min();
  std::vector<Observation> rows;
  while (csv.next(5)) {
    Observation o;
    o.stop = checkedIndex(csv, 0, "stop", 0);
    o.sensor = checkedIndex(csv, 1, "sensor", kAnyInt);
    o.landmark = checkedIndex(csv, 2, "landmark", kAnyInt);
    o.range_m = csv.number(3, "range_m");
    o.bearing_rad = csv.number(4, "bearing_rad");
    rows.push_back(o);
  }
  std::vector<int> sensors = relabel(rows, &Observation::sensor, false);
  std::vector<int> landmarks = relabel(rows, &Observation::landmark, true);
  if (sensor_labels) *sensor_labels = std::move(sensors);
  if (landmark_labels) *landmark_labels = std::move(landmarks);
  return rows;
}

void writeObservations(const std::filesystem::path& file, const std::vector<Observation>& rows) {
  std::string text = std::string(kObservationsHeader) + "\n";
  text.reserve(rows.size() * 48 + text.size());
  char line[128];
  for (const auto& o : rows) {
    std::snprintf(line, sizeof line, "%d,%d,%d,%.12g,%.12g\n", o.stop, o.sensor, o.landmark,
                  o.range_m, o.bearing_rad);
    text += line;
  }
  writeTextAtomically(file, text);
}

std::vector<OdometryStep> readOdometry(const std::filesystem::path& file) {
  CsvReader csv(file, kRemedy);
  csv.expectHeader(kOdometryHeader);
  std::vector<OdometryStep> rows;
  while (csv.next(4)) {
    OdometryStep s;
    s.stop = checkedIndex(csv, 0, "stop", 0);
    if (s.stop != static_cast<int>(rows.size()))
      csv.fail("stop", "expected stop " + std::to_string(rows.size()) +
                           " (rows must list stops 0, 1, 2, ... in order)");
    s.dx_m = csv.number(1, "dx_m");
    s.dy_m = csv.number(2, "dy_m");
    s.dtheta_rad = csv.number(3, "dtheta_rad");
    if (s.stop == 0 && (s.dx_m != 0.0 || s.dy_m != 0.0 || s.dtheta_rad != 0.0))
      csv.fail("dx_m", "stop 0 is the start: its motion must be 0,0,0");
    rows.push_back(s);
  }
  if (rows.empty())
    throw InputError(file.string(), "", "holds no stop (at least the start, stop 0, is needed)",
                     kRemedy);
  return rows;
}

void writeOdometry(const std::filesystem::path& file, const std::vector<OdometryStep>& rows) {
  std::string text = std::string(kOdometryHeader) + "\n";
  char line[128];
  for (const auto& s : rows) {
    std::snprintf(line, sizeof line, "%d,%.12g,%.12g,%.12g\n", s.stop, s.dx_m, s.dy_m,
                  s.dtheta_rad);
    text += line;
  }
  writeTextAtomically(file, text);
}

}  // namespace lidarcal::io
