// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What a user can do with a recording that calibrate or run refused: the ways forward that exist
// for that recording, named in the refusal (docs/ERRORS.md). A recording made from one place
// cannot self-calibrate, but it can be calibrated against wall-to-wall spans or tape distances
// measured there (calibrate --reference), and diagnose can criticise the model on it; what to
// record for a self-calibration comes last.

#include <string>

#include "common/status.hpp"
#include "io/sequence.hpp"

namespace lidarcal::pipeline {

/// The remedy of a refusal with `code` for `seq`: for a recording from one place (one stop, or
/// stops that never moved), calibrate --reference with spans or distances (listing the walls
/// stop 0 shows, with their normal directions, to name in REF.json), diagnose, and what to
/// record; for other refusals the reference fit and detect where they help; always docs/ERRORS.md.
std::string waysForward(const io::Sequence& seq, StatusCode code);

/// "131 deg at 2.34 m, -50 deg at 3.44 m, ...": the walls the first scans of stop `stop` show
/// (normal direction in the sensor frame, perpendicular distance as read), "none" without any.
std::string wallsSeen(const io::Sequence& seq, std::size_t stop);

}  // namespace lidarcal::pipeline
