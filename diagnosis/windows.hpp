// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What part of a recording a diagnosis reads, and how: a long sequence cut to its leading stops,
// the stop whose repeated scans static mode reads by default, and those scans' readings (through
// a calibrated model's inverse when one is given, to diagnose what that model still gets wrong).

#include <cmath>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>

#include "calibration/inversion.hpp"
#include "common/landmark_observations.hpp"
#include "diagnosis/static_scene.hpp"
#include "io/sequence.hpp"

namespace lidarcal::diagnosis {

/// Readings corrected through a calibrated model's inverse; without one, readings pass unchanged.
struct ReadingCorrection {
  /// the model's inverse (empty: no correction)
  std::optional<calibration::RangeInverter> inverter;
  /// The corrected reading (NaN where the inverse has no root).
  double correct(double y) const {
    if (!inverter) return y;
    const auto d = inverter->invert(y);
    return d ? *d : std::nan("");
  }
};

/// A long log cut to its leading stops that hold at most `max_readings` landmark readings (none
/// cut when 0; two stops at least). A sequence diagnosis refits the joint problem for every
/// replica, candidate and fold, each fit costing about a microsecond per reading and iteration, so
/// a long log is cut (docs/results/hidden-effects.md, Cost); the report says the window. Returns
/// the selection's words (empty when nothing was cut).
std::string leadingWindow(LandmarkObservations& obs, std::size_t max_readings);

/// Every reading of every sighting through `fix` (nothing to do without an inverse).
void correctReadings(LandmarkObservations& obs, const ReadingCorrection& fix);

/// The stop with the most scans (the first of equals): the one static mode reads by default.
std::size_t busiestStop(const io::Sequence& seq);

/// The readings of the scans of stop `stop`, each through `fix`, with the scans' median beam
/// count, their intensities when recorded, and the sensor window; on_scan(done) after each scan.
StaticScans staticScans(const io::Sequence& seq, std::size_t stop, const ReadingCorrection& fix,
                        const std::function<void(std::size_t)>& on_scan);

}  // namespace lidarcal::diagnosis
