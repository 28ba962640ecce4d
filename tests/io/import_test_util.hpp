// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Helpers for the importer tests: gzip files, collecting the scans an importer hands on.

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <zlib.h>

#include "io/import.hpp"

namespace lidarcal::test {

/// Writes `text` gzip-compressed (zlib, independent of the code under test).
inline void writeGzip(const std::filesystem::path& file, const std::string& text) {
  gzFile f = gzopen(file.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(gzwrite(f, text.data(), static_cast<unsigned>(text.size())),
            static_cast<int>(text.size()));
  ASSERT_EQ(gzclose(f), Z_OK);
}

/// Keeps a copy of every scan (test inputs are small); optionally asks to stop after `stop_after`.
struct Collector {
  std::vector<io::RawScan> scans;
  std::size_t stop_after = 0;  // 0 = never stop
  io::ScanCallback callback() {
    return [this](const io::RawScan& s) {
      scans.push_back(s);
      return stop_after == 0 || scans.size() < stop_after;
    };
  }
};

/// Bearing and range of a point in the sensor frame.
inline double bearingOf(float x, float y) {
  return std::atan2(static_cast<double>(y), static_cast<double>(x));
}
inline double rangeOf(float x, float y) {
  return std::hypot(static_cast<double>(x), static_cast<double>(y));
}

/// Angle difference wrapped to (-pi, pi].
inline double angleDiff(double a, double b) {
  double d = std::fmod(a - b + M_PI, 2.0 * M_PI);
  if (d <= 0.0) d += 2.0 * M_PI;
  return d - M_PI;
}

}  // namespace lidarcal::test
