// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The discrepancy statistics of a static recording (diagnosis/battery.hpp lists them): the
// noise against range, incidence, intensity and bearing, a shared trend over the scans, the
// readings' independence, edges, tails, the reading grid, and the walls' shape. Internal to the
// diagnosis library.

#include <map>
#include <string>
#include <vector>

#include "diagnosis/static_scene/reading_model.hpp"
#include "diagnosis/static_scene/wall_model.hpp"

namespace lidarcal::diagnosis::static_scene {

/// Every statistic of the battery under the model m with bin locations f, the wall model without
/// (w0) and with (wb) the incidence bias, and the reading grid q (0: none).
std::map<std::string, double> staticStatistics(const BinnedReadings& d,
                                               const std::vector<BinFit>& f, const ReadingModel& m,
                                               const WallFit& w0, const WallFit& wb, double q);

}  // namespace lidarcal::diagnosis::static_scene
