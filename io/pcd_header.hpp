// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Private to the PCD reader (pcd_scan.cpp): a PCD header parsed and checked before PCL sees the
// file, with the messages a damaged or foreign file gets.

#include <cstddef>
#include <istream>
#include <string>
#include <vector>

#include "common/pose2.hpp"

namespace lidarcal::io::pcd {

constexpr std::size_t kMaxHeaderBytes = 1 << 16;  ///< a PCD header is a few hundred bytes
constexpr std::size_t kMaxPoints = 100'000'000;   ///< refuse absurd POINTS before allocating
constexpr double kMaxAbsCoordinate_m = 1.0e5;     ///< no lidar of ours sees 100 km

constexpr const char* kFormatRemedy = "see docs/FORMAT.md for the scan file format";

/// One field of FIELDS with its SIZE (bytes), TYPE (F, I or U) and COUNT.
struct HeaderField {
  std::string name;  ///< field name (x, y, z, intensity, ...)
  int size = 0;      ///< bytes per value: 1, 2, 4 or 8
  char type = '?';   ///< F (float), I (signed) or U (unsigned)
  int count = 1;     ///< values per point
};

/// A checked header: its fields, the cloud's dimensions, the VIEWPOINT and where DATA begins.
struct ParsedHeader {
  std::vector<HeaderField> fields;  ///< in the order of FIELDS
  /// as given; HEIGHT defaults to 1, POINTS to WIDTH x HEIGHT
  long long width = -1, height = -1, points = -1;
  bool has_viewpoint = false;                   ///< a VIEWPOINT line was given
  double viewpoint[7] = {0, 0, 0, 1, 0, 0, 0};  ///< tx ty tz qw qx qy qz
  std::string data;                             ///< ascii, binary or binary_compressed
  std::size_t data_offset = 0;                  ///< byte offset of the first data byte
};

/// Words separated by white space, as `>>` splits them.
std::vector<std::string> splitWords(const std::string& line);

/// A word of a damaged file as it can be shown in a message: at most 24 characters, anything
/// but printable ASCII as '?'.
std::string printable(const std::string& word);

/// The whole of `text` as a base-10 integer; false when it is not one.
bool parseLong(const std::string& text, long long& value);

/// The whole of `text` as a number; false when it is not one.
bool parseDouble(const std::string& text, double& value);

/// The header's lines up to DATA, checked (the stream positioned at its start). Throws
/// InputError naming `where` and the line or keyword at fault.
ParsedHeader parseHeader(std::istream& in, const std::string& where);

/// The field called `name`, or nullptr.
const HeaderField* findField(const ParsedHeader& h, const std::string& name);

/// The sensor pose of the VIEWPOINT (a yaw rotation only); throws InputError when missing or not
/// planar.
Pose2 viewpointPose(const ParsedHeader& h, const std::string& where);

/// Throws InputError when field `name` is not a single float (or is missing and `required`).
void checkCoordinateField(const ParsedHeader& h, const std::string& name, bool required,
                          const std::string& where);

}  // namespace lidarcal::io::pcd
