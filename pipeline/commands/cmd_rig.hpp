// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The rig (several sensors on one vehicle) side of `import`, `calibrate` and `correct`: each
// command hands over here when it meets several topics, a rig sequence or a rig model
// (cmd_rig_import.cpp, cmd_rig_calibrate.cpp, cmd_rig_correct.cpp). Executable-internal.

#include <string>
#include <vector>

#include "pipeline/commands/cli_options.hpp"
#include "pipeline/stages/rig_import.hpp"

namespace lidarcal::pipeline {

/// `import --topic T1,T2,...`: imports and prints what was written.
void runRigImport(const RigImportSettings& settings);

/// `calibrate RIG`: the rig's options besides the single-sensor ones it shares.
struct RigCalibrateSettings {
  std::string dir, out;
  bool overwrite = false;
  CalibrationOptions options;  ///< --radius, --inlier-threshold, --motion-prior apply
  std::string frame = "auto";  ///< --rig-frame auto|vehicle|relative
  std::string reference;       ///< --reference-sensor (default: the first)
  double min_intensity = 0.0;  ///< --min-intensity (retro-reflectors)
  double associate_m = 0.3;    ///< --associate, metres
};

/// `calibrate RIG --out model.json`: detects, associates, calibrates, writes the rig model and
/// prints the mountings against tf_static. Throws DataError (exit 3) when the data cannot give
/// them.
void runRigCalibrate(const RigCalibrateSettings& settings);

/// Topics listed with commas (`--topic /a,/b`); one topic gives one element.
std::vector<std::string> splitList(const std::string& text);

}  // namespace lidarcal::pipeline
