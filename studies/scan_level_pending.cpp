// Placeholder until the detectors library is merged into this branch: the scan level needs
// detectors::detectSequence (studies/scan_level.cpp replaces this file then).
#include <stdexcept>

#include "studies/scan_level.hpp"
#include "studies/trial.hpp"

namespace lidarcal::studies {

void ScanLevelConfig::validate() const {}

ScanLevelConfig scanLevelConfig(const TrialConfig& config) {
  ScanLevelConfig c;
  c.beams = config.scan_beams;
  return c;
}

Draw drawScanLevel(const std::vector<Cylinder>&, const PathSpec&, const RangeModel&, const ScanLevelConfig&, std::uint64_t, bool) {
  throw std::runtime_error("the scan level needs the detectors library (not merged yet)");
}

}  // namespace lidarcal::studies
