// SPDX-License-Identifier: BSD-3-Clause
#include "io/true_ranges.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string_view>

#include "common/errors.hpp"
#include "io/text_fields.hpp"

namespace lidarcal::io {

namespace {
constexpr const char* kHeader = "scan,beam,true_range_m,target,target_id,incidence_rad";
}

const char* toString(TargetKind kind) {
  switch (kind) {
    case TargetKind::none:
      return "none";
    case TargetKind::landmark:
      return "landmark";
    case TargetKind::clutter:
      return "clutter";
    case TargetKind::wall:
      return "wall";
  }
  return "none";
}

TrueRangesWriter::TrueRangesWriter(const std::filesystem::path& file)
    : file_(file), out_(file, std::ios::trunc) {
  if (!out_)
    throw InputError(file.string(), "", "cannot be created",
                     "check that the directory is writable");
  out_ << kHeader << '\n';
}

void TrueRangesWriter::write(const TrueRange& r) {
  char line[160];
  if (std::isnan(r.range_m))
    std::snprintf(line, sizeof line, "%u,%u,nan,none,0,nan\n", r.scan, r.beam);
  else
    std::snprintf(line, sizeof line, "%u,%u,%.7f,%s,%d,%.6f\n", r.scan, r.beam, r.range_m,
                  toString(r.target), r.target_id, r.incidence_rad);
  out_ << line;
}

void TrueRangesWriter::close() {
  out_.close();
  if (!out_)
    throw InputError(file_.string(), "", "write failed (disk full?)",
                     "free some space and run again");
}

std::vector<TrueRange> readTrueRanges(const std::filesystem::path& file) {
  constexpr const char* kRemedy =
      "see docs/FORMAT.md (true_ranges.csv); it is written by `lidarcal simulate`";
  std::ifstream in(file);
  if (!in)
    throw InputError(file.string(), "", "cannot be opened",
                     "it is written by `lidarcal simulate` next to truth.json");
  std::string line;
  if (!std::getline(in, line) || line != kHeader)
    throw InputError(file.string(), "line 1", std::string("header must be `") + kHeader + "`",
                     "see docs/FORMAT.md");
  std::vector<TrueRange> rows;
  std::vector<std::string_view> f;
  static const char* const kNames[] = {"scan",   "beam",      "true_range_m",
                                       "target", "target_id", "incidence_rad"};
  for (std::size_t line_no = 2; std::getline(in, line); ++line_no) {
    if (line.empty()) continue;
    const std::string where = "line " + std::to_string(line_no);
    splitCommas(line, f);
    if (f.size() != 6)
      throw InputError(file.string(), where, "expected 6 comma-separated values", kRemedy);
    const auto fail = [&](std::size_t k, const std::string& problem) {
      throw InputError(file.string(), where + ", column " + kNames[k],
                       "`" + std::string(f[k]) + "` " + problem, kRemedy);
    };
    const auto number = [&](std::size_t k) {
      double v = 0.0;
      if (!parseNumber(f[k], v) || std::isinf(v)) fail(k, "is not a number (nan allowed)");
      return v;
    };
    const auto index = [&](std::size_t k) {
      const double v = number(k);
      if (!(v >= 0.0) || v != std::floor(v) || v > 4294967295.0)
        fail(k, "is not an integer from 0 to 2^32-1");
      return static_cast<std::uint32_t>(v);
    };
    TrueRange r;
    r.scan = index(0);
    r.beam = index(1);
    r.range_m = number(2);
    const std::string_view t = f[3];
    r.target = t == "landmark"  ? TargetKind::landmark
               : t == "clutter" ? TargetKind::clutter
               : t == "wall"    ? TargetKind::wall
                                : TargetKind::none;
    if (r.target == TargetKind::none && t != "none")
      fail(3, "is not one of none, landmark, clutter, wall");
    const std::uint32_t id = index(4);
    if (id > 2147483647u) fail(4, "is too large");
    r.target_id = static_cast<int>(id);
    r.incidence_rad = number(5);
    if (r.range_m < 0.0) fail(2, "is negative");
    rows.push_back(r);
  }
  return rows;
}

}  // namespace lidarcal::io
