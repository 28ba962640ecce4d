// SPDX-License-Identifier: BSD-3-Clause
#include "io/pcd_header.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "common/errors.hpp"

namespace lidarcal::io::pcd {
namespace {

/// PCL's header reader does not stop at DATA: it goes on reading lines, skips empty ones and
/// comments, and takes any line whose first word begins with a header keyword as more header
/// (more FIELDS, another DATA), until a line that is none of these. Binary data that happens to
/// read like that would make PCL load something else than the header we checked (found by
/// fuzzing: a `COLUMNS` line at the start of binary data gave PCL one garbage field and no x).
void checkNothingAfterData(std::istream& in, const std::string& where, std::size_t consumed) {
  static const char* const kKeywords[] = {"VERSION",   "FIELDS", "COLUMNS", "SIZE",
                                          "TYPE",      "COUNT",  "WIDTH",   "HEIGHT",
                                          "VIEWPOINT", "POINTS", "DATA"};
  const auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  std::string line;
  while (consumed < kMaxHeaderBytes && std::getline(in, line)) {
    consumed += line.size() + 1;
    if (line.empty()) continue;
    std::size_t b = 0;
    while (b < line.size() && space(line[b])) ++b;
    std::size_t e = b;
    while (e < line.size() && !space(line[e])) ++e;
    const std::string word = line.substr(b, e - b);
    if (word.empty()) return;      // PCL stops at a blank line
    if (word[0] == '#') continue;  // and skips comments
    for (const char* k : kKeywords)
      if (word.compare(0, std::strlen(k), k) == 0)
        throw InputError(where, "DATA",
                         "the data begins with a line PCL would read as more header ('" +
                             printable(word) + "'): a damaged file",
                         "re-export the scan");
    return;
  }
}

/// The header's lines as read, before the per-field checks.
struct HeaderLines {
  std::vector<std::string> sizes, types, counts;
  bool seen_fields = false, seen_size = false, seen_type = false;
  std::size_t consumed = 0;  ///< bytes up to and including the DATA line
};

/// One WIDTH, HEIGHT, POINTS or VIEWPOINT line into the header.
void parseDimensionOrViewpoint(ParsedHeader& h, const std::string& key,
                               const std::vector<std::string>& words, const std::string& item,
                               const std::string& where) {
  if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
    long long v = 0;
    if (words.size() != 1 || !parseLong(words[0], v) || v < 0)
      throw InputError(where, item, "expected one non-negative integer", kFormatRemedy);
    (key == "WIDTH" ? h.width : key == "HEIGHT" ? h.height : h.points) = v;
    return;
  }
  if (words.size() != 7)
    throw InputError(
        where, "VIEWPOINT",
        "expected 7 numbers `tx ty tz qw qx qy qz`, found " + std::to_string(words.size()),
        kFormatRemedy);
  for (int i = 0; i < 7; ++i)
    if (!parseDouble(words[static_cast<std::size_t>(i)], h.viewpoint[i]) ||
        !std::isfinite(h.viewpoint[i]))
      throw InputError(
          where, "VIEWPOINT",
          "value '" + printable(words[static_cast<std::size_t>(i)]) + "' is not a finite number",
          kFormatRemedy);
  h.has_viewpoint = true;
}

/// Reads the header's lines up to and including DATA into `h` and the returned lines.
HeaderLines readHeaderLines(std::istream& in, const std::string& where, ParsedHeader& h) {
  HeaderLines lines;
  std::string line;
  std::size_t& consumed = lines.consumed;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    consumed += line.size() + 1;
    if (consumed > kMaxHeaderBytes)
      throw InputError(where, "header",
                       "no DATA line in the first 64 KiB: not a PCD file or a damaged one",
                       kFormatRemedy);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    auto words = splitWords(line);
    if (words.empty()) continue;
    const std::string key = words[0];
    const std::string item = "header line " + std::to_string(line_no) + " (" + printable(key) + ")";
    words.erase(words.begin());
    if (key == "VERSION") {
      continue;
    } else if (key == "FIELDS" || key == "COLUMNS") {
      lines.seen_fields = true;
      for (const auto& w : words) h.fields.push_back({w});
    } else if (key == "SIZE") {
      lines.seen_size = true;
      lines.sizes = words;
    } else if (key == "TYPE") {
      lines.seen_type = true;
      lines.types = words;
    } else if (key == "COUNT") {
      lines.counts = words;
    } else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS" || key == "VIEWPOINT") {
      parseDimensionOrViewpoint(h, key, words, item, where);
    } else if (key == "DATA") {
      if (words.size() != 1 ||
          (words[0] != "ascii" && words[0] != "binary" && words[0] != "binary_compressed"))
        throw InputError(where, "DATA", "must be ascii, binary or binary_compressed",
                         kFormatRemedy);
      h.data = words[0];
      h.data_offset = consumed;
      break;
    } else {
      throw InputError(where, item, "unknown header keyword: not a PCD file or a damaged one",
                       kFormatRemedy);
    }
  }
  return lines;
}

/// SIZE, TYPE and COUNT: one per field, each valid, into the fields.
void checkFieldLayout(ParsedHeader& h, const HeaderLines& lines, const std::string& where) {
  const auto& sizes = lines.sizes;
  const auto& types = lines.types;
  const auto& counts = lines.counts;
  if (!lines.seen_fields || h.fields.empty())
    throw InputError(where, "FIELDS", "missing", kFormatRemedy);
  if (!lines.seen_size || sizes.size() != h.fields.size())
    throw InputError(where, "SIZE",
                     "must give one size per field (" + std::to_string(h.fields.size()) + ")",
                     kFormatRemedy);
  if (!lines.seen_type || types.size() != h.fields.size())
    throw InputError(where, "TYPE",
                     "must give one type per field (" + std::to_string(h.fields.size()) + ")",
                     kFormatRemedy);
  if (!counts.empty() && counts.size() != h.fields.size())
    throw InputError(where, "COUNT",
                     "must give one count per field (" + std::to_string(h.fields.size()) + ")",
                     kFormatRemedy);
  for (std::size_t i = 0; i < h.fields.size(); ++i) {
    long long size = 0, count = 1;
    if (!parseLong(sizes[i], size) || (size != 1 && size != 2 && size != 4 && size != 8))
      throw InputError(where, "SIZE of field '" + h.fields[i].name + "'", "must be 1, 2, 4 or 8",
                       kFormatRemedy);
    if (types[i].size() != 1 || std::string("FIU").find(types[i][0]) == std::string::npos)
      throw InputError(where, "TYPE of field '" + h.fields[i].name + "'", "must be F, I or U",
                       kFormatRemedy);
    if (!counts.empty() && (!parseLong(counts[i], count) || count < 1 || count > 1'000'000))
      throw InputError(where, "COUNT of field '" + h.fields[i].name + "'",
                       "must be a positive integer", kFormatRemedy);
    h.fields[i].size = static_cast<int>(size);
    h.fields[i].type = types[i][0];
    h.fields[i].count = static_cast<int>(count);
  }
}

/// WIDTH given, HEIGHT and POINTS defaulted, POINTS = WIDTH x HEIGHT and not absurd.
void checkDimensions(ParsedHeader& h, const std::string& where) {
  if (h.width < 0) throw InputError(where, "WIDTH", "missing", kFormatRemedy);
  if (h.height < 0) h.height = 1;
  if (h.points < 0) h.points = h.width * h.height;
  if (h.width > static_cast<long long>(kMaxPoints) ||
      h.height > static_cast<long long>(kMaxPoints) || h.points != h.width * h.height)
    throw InputError(where, "POINTS",
                     "POINTS (" + std::to_string(h.points) + ") differs from WIDTH x HEIGHT (" +
                         std::to_string(h.width) + " x " + std::to_string(h.height) + ")",
                     kFormatRemedy);
  if (h.points > static_cast<long long>(kMaxPoints))
    throw InputError(where, "POINTS", "more than 100 million points: refusing to load",
                     kFormatRemedy);
}

}  // namespace

std::vector<std::string> splitWords(const std::string& line) {
  // Words separated by white space, as `>>` splits them (without a stream per line: every scan's
  // header is parsed when a sequence is opened and again when the scan is read).
  const auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  std::vector<std::string> words;
  for (std::size_t i = 0; i < line.size();) {
    while (i < line.size() && space(line[i])) ++i;
    std::size_t e = i;
    while (e < line.size() && !space(line[e])) ++e;
    if (e > i) words.emplace_back(line, i, e - i);
    i = e;
  }
  return words;
}

std::string printable(const std::string& word) {
  std::string out;
  for (char c : word.substr(0, 24)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  return word.size() > 24 ? out + "..." : out;
}

bool parseLong(const std::string& text, long long& value) {
  char* end = nullptr;
  errno = 0;
  value = std::strtoll(text.c_str(), &end, 10);
  return errno == 0 && end != text.c_str() && *end == '\0';
}

bool parseDouble(const std::string& text, double& value) {
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0';
}

ParsedHeader parseHeader(std::istream& in, const std::string& where) {
  ParsedHeader h;
  const HeaderLines lines = readHeaderLines(in, where, h);
  if (h.data.empty())
    throw InputError(where, "DATA", "header has no DATA line: truncated or not a PCD file",
                     kFormatRemedy);
  checkNothingAfterData(in, where, lines.consumed);
  checkFieldLayout(h, lines, where);
  checkDimensions(h, where);
  return h;
}

const HeaderField* findField(const ParsedHeader& h, const std::string& name) {
  for (const auto& f : h.fields)
    if (f.name == name) return &f;
  return nullptr;
}

Pose2 viewpointPose(const ParsedHeader& h, const std::string& where) {
  if (!h.has_viewpoint)
    throw InputError(where, "VIEWPOINT", "missing: every scan must carry the commanded sensor pose",
                     "write `VIEWPOINT tx ty 0 qw 0 0 qz` into the header, see docs/FORMAT.md");
  const double* v = h.viewpoint;
  const double norm = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
  if (std::abs(norm - 1.0) > 1e-3)
    throw InputError(
        where, "VIEWPOINT",
        "quaternion (qw qx qy qz) is not of unit length (norm " + std::to_string(norm) + ")",
        kFormatRemedy);
  if (std::abs(v[4]) > 1e-3 || std::abs(v[5]) > 1e-3)
    throw InputError(where, "VIEWPOINT",
                     "quaternion has roll/pitch (qx, qy not 0): only a yaw rotation is allowed",
                     kFormatRemedy);
  Pose2 pose;
  pose.x_m = v[0];
  pose.y_m = v[1];
  pose.yaw_rad = wrapAngle(2.0 * std::atan2(v[6], v[3]));
  return pose;
}

void checkCoordinateField(const ParsedHeader& h, const std::string& name, bool required,
                          const std::string& where) {
  const HeaderField* f = findField(h, name);
  if (!f) {
    if (required)
      throw InputError(where, "FIELDS",
                       "no '" + name + "' field: scans need at least x and y (and normally z)",
                       kFormatRemedy);
    return;
  }
  if (f->type != 'F' || (f->size != 4 && f->size != 8) || f->count != 1)
    throw InputError(where, "field '" + name + "'",
                     "must be a single float (TYPE F, SIZE 4 or 8, COUNT 1)", kFormatRemedy);
}

}  // namespace lidarcal::io::pcd
