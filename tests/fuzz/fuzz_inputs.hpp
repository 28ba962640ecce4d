// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One function per fuzzed reader: hand it any bytes; it writes them to a scratch file, runs the
// reader and accepts a result or an InputError. Anything else (a crash, a sanitizer report, an
// exception of another type, a hang) is a finding. Used by the libFuzzer targets (fuzz_main.cpp,
// LIDARCAL_FUZZ) and by test_fuzz_regressions, which replays the seed corpora and every past
// finding (tests/fuzz/corpus/<target>/, tests/fuzz/regressions/<target>/) in the normal build.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace lidarcal::fuzz {

/// A fuzzed reader: bytes in, nothing out; throws only when a reader broke its contract.
using Target = void (*)(const std::uint8_t* data, std::size_t size);

struct NamedTarget {
  const char* name;  ///< fuzz_<name> binary, corpus/<name>/, regressions/<name>/
  Target run;
};

/// Every target: pcd, json, csv, carmen, ydlidar, csv_import, mcap (MCAP reader + ROS 2 import),
/// cdr (ROS 2 message decoders).
const std::vector<NamedTarget>& targets();

}  // namespace lidarcal::fuzz
