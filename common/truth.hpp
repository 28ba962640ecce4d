// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Ground truth of a simulated sequence. Written beside the sequence (DIR/truth.json), never
// inside it; only evaluation and oracle calibration read it.

#include <cstdint>
#include <string>
#include <vector>

#include "common/pose2.hpp"
#include "common/scene.hpp"

namespace lidarcal {

/// One stop of a simulated sequence.
struct TruthStop {
  Pose2 commanded;  ///< pose written to VIEWPOINT
  Pose2 actual;     ///< pose the sensor really had (commanded + sigma_s, sigma_psi noise)
  std::size_t first_scan = 0;  ///< index of the stop's first scan in the sequence
  std::size_t scans = 0;       ///< number of scans at this stop
};

struct Truth {
  std::uint64_t seed = 0;        ///< simulator seed
  Scene scene;                   ///< the scene simulated (landmark ids are 1..L in scene order)
  std::vector<TruthStop> stops;  ///< per stop
  std::string true_ranges_file = "true_ranges.csv";  ///< companion file, relative to truth.json
};

}  // namespace lidarcal
