#include "io/true_ranges.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "common/errors.hpp"

namespace lidarcal::io {

namespace {
constexpr const char* kHeader = "scan,beam,true_range_m,target,target_id,incidence_rad";
}

const char* toString(TargetKind kind) {
  switch (kind) {
    case TargetKind::none: return "none";
    case TargetKind::landmark: return "landmark";
    case TargetKind::clutter: return "clutter";
    case TargetKind::wall: return "wall";
  }
  return "none";
}

TrueRangesWriter::TrueRangesWriter(const std::filesystem::path& file) : file_(file), out_(file, std::ios::trunc) {
  if (!out_) throw InputError(file.string(), "", "cannot be created", "check that the directory is writable");
  out_ << kHeader << '\n';
}

void TrueRangesWriter::write(const TrueRange& r) {
  char line[160];
  if (std::isnan(r.range_m))
    std::snprintf(line, sizeof line, "%u,%u,nan,none,0,nan\n", r.scan, r.beam);
  else
    std::snprintf(line, sizeof line, "%u,%u,%.7f,%s,%d,%.6f\n", r.scan, r.beam, r.range_m, toString(r.target),
                  r.target_id, r.incidence_rad);
  out_ << line;
}

void TrueRangesWriter::close() {
  out_.flush();
  if (!out_) throw InputError(file_.string(), "", "write failed (disk full?)", "free some space and run again");
  out_.close();
}

std::vector<TrueRange> readTrueRanges(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "", "cannot be opened", "it is written by `lidarcal simulate` next to truth.json");
  std::string line;
  if (!std::getline(in, line) || line != kHeader)
    throw InputError(file.string(), "line 1", std::string("header must be `") + kHeader + "`", "see docs/FORMAT.md");
  std::vector<TrueRange> rows;
  std::size_t line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    TrueRange r;
    char target[16] = {0};
    char range_text[32] = {0}, incidence_text[32] = {0};
    if (std::sscanf(line.c_str(), "%u,%u,%31[^,],%15[^,],%d,%31s", &r.scan, &r.beam, range_text, target, &r.target_id,
                    incidence_text) != 6)
      throw InputError(file.string(), "line " + std::to_string(line_no), "expected 6 comma-separated values",
                       "see docs/FORMAT.md");
    r.range_m = std::strtod(range_text, nullptr);
    r.incidence_rad = std::strtod(incidence_text, nullptr);
    const std::string t = target;
    r.target = t == "landmark" ? TargetKind::landmark : t == "clutter" ? TargetKind::clutter
             : t == "wall"     ? TargetKind::wall     : TargetKind::none;
    rows.push_back(r);
  }
  return rows;
}

}  // namespace lidarcal::io
