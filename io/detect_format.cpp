// SPDX-License-Identifier: BSD-3-Clause
#include "io/detect_format.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include <zlib.h>

#include "common/errors.hpp"

namespace lidarcal::io {
namespace {

constexpr std::size_t kPeekBytes = 64 * 1024;

/// Up to kPeekBytes of the content (gzip inflated; zlib reads other files as they are).
std::string peekContent(const std::filesystem::path& file) {
  gzFile gz = gzopen(file.c_str(), "rb");
  if (!gz) return {};
  std::string buf(kPeekBytes, '\0');
  const int n = gzread(gz, buf.data(), static_cast<unsigned>(buf.size()));
  gzclose(gz);
  buf.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
  return buf;
}

bool isCarmenKeyword(const std::string& word) {
  static const char* const kKeywords[] = {
      "PARAM",       "SYNC",      "ODOM",      "FLASER",    "RLASER",    "LASER3",
      "LASER4",      "RAWLASER1", "RAWLASER2", "RAWLASER3", "RAWLASER4", "ROBOTLASER1",
      "ROBOTLASER2", "TRUEPOS",   "NMEAGGA",   "NMEARMC",   "GPSNMEA"};
  return std::any_of(std::begin(kKeywords), std::end(kKeywords),
                     [&](const char* k) { return word == k; });
}

bool isNumber(std::string field) {
  field.erase(0, field.find_first_not_of(" \t"));
  field.erase(field.find_last_not_of(" \t\r") + 1);
  if (field.empty()) return false;
  char* end = nullptr;
  std::strtod(field.c_str(), &end);
  return end && *end == '\0';
}

std::vector<std::string> splitCommas(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string f;
  while (std::getline(ss, f, ',')) out.push_back(f);
  return out;
}

DetectedFormat fromText(const std::string& text, DetectedFormat d) {
  std::istringstream in(text);
  std::string line;
  bool complete = true;
  while (std::getline(in, line)) {
    complete = !in.eof() || text.size() < kPeekBytes;  // the last line may be cut at the peek limit
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    for (char c : line)
      // binary: unknown
      if (c == '\0' || (static_cast<unsigned char>(c) < 0x20 && c != '\t')) return d;
    std::istringstream words(line);
    std::string word;
    words >> word;
    if (isCarmenKeyword(word)) {
      d.kind = RecordingKind::carmen;
      d.evidence = "its first record line starts with the CARMEN keyword " + word;
      return d;
    }
    const auto fields = splitCommas(line);
    if (fields.size() >= 2 && std::none_of(fields.begin(), fields.end(), isNumber)) {
      auto names = [&](const char* name) {
        return std::any_of(fields.begin(), fields.end(), [&](std::string f) {
          f.erase(0, f.find_first_not_of(" \t"));
          f.erase(f.find_last_not_of(" \t") + 1);
          return f == name;
        });
      };
      if (names("range_m") && names("angle_rad")) {
        d.kind = RecordingKind::csv;
        d.evidence = "its first line is a CSV header naming angle_rad and range_m";
      }
      return d;
    }
    if (fields.size() >= 4 && (complete || fields.size() > 4) &&
        std::all_of(fields.begin(), fields.end() - (complete ? 0 : 1), isNumber)) {
      d.kind = RecordingKind::ydlidar;
      d.evidence = "its rows are " +
                   std::string(complete ? std::to_string(fields.size()) : "many") +
                   " comma-separated numbers without a header (distance, dtheta, dt, ranges)";
    }
    return d;
  }
  return d;
}

}  // namespace

const char* toString(RecordingKind kind) {
  switch (kind) {
    case RecordingKind::rosbag1:
      return "rosbag1";
    case RecordingKind::mcap:
      return "mcap";
    case RecordingKind::rosbag2:
      return "rosbag2";
    case RecordingKind::carmen:
      return "carmen";
    case RecordingKind::ydlidar:
      return "ydlidar";
    case RecordingKind::csv:
      return "csv";
    case RecordingKind::unknown:
      break;
  }
  return "unknown";
}

DetectedFormat detectRecordingFormat(const std::filesystem::path& file) {
  std::error_code ec;
  DetectedFormat d;
  if (std::filesystem::is_directory(file, ec)) {
    if (!std::filesystem::is_regular_file(file / "metadata.yaml", ec))
      throw InputError(
          file.string(), "",
          "is a directory without metadata.yaml (not a ROS 2 bag), expected a recording file",
          "give the path of the recording");
    d.kind = RecordingKind::rosbag2;
    d.evidence = "it is a directory with metadata.yaml (a ROS 2 bag)";
    return d;
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    if (!std::filesystem::exists(file, ec))
      throw InputError(file.string(), "", "file does not exist", "check the path");
    throw InputError(file.string(), "", "cannot be opened for reading", "check its permissions");
  }
  char head[16] = {};
  in.read(head, sizeof head);
  const std::string magic(head, static_cast<std::size_t>(in.gcount()));
  if (magic.rfind("#ROSBAG V2.0", 0) == 0) {
    d.kind = RecordingKind::rosbag1;
    d.evidence = "it starts with #ROSBAG V2.0";
    return d;
  }
  if (magic.rfind("\x89MCAP0\r\n", 0) == 0) {
    d.kind = RecordingKind::mcap;
    d.evidence = "it starts with the MCAP magic";
    return d;
  }
  if (magic == std::string("SQLite format 3\0", 16)) {
    d.kind = RecordingKind::rosbag2;
    d.evidence = "it is an SQLite database (a ROS 2 .db3 bag file)";
    return d;
  }
  d.gzip = magic.size() >= 2 && static_cast<unsigned char>(magic[0]) == 0x1f &&
           static_cast<unsigned char>(magic[1]) == 0x8b;
  return fromText(peekContent(file), d);
}

}  // namespace lidarcal::io
