#pragma once
// The rig (several sensors on one vehicle) side of `import`, `calibrate` and `correct`: each
// command hands over here when it meets several topics, a rig sequence or a rig model
// (cmd_rig_import.cpp, cmd_rig_calibrate.cpp, cmd_rig_correct.cpp). Executable-internal.

#include <string>
#include <vector>

#include "pipeline/rig_import.hpp"

namespace lidarcal::pipeline {

/// `import --topic T1,T2,...`: imports and prints what was written.
void runRigImport(const RigImportSettings& settings);

/// Topics listed with commas (`--topic /a,/b`); one topic gives one element.
std::vector<std::string> splitList(const std::string& text);

}  // namespace lidarcal::pipeline
