#pragma once
// The sightings of a sequence's detections (detectors/sightings.hpp) under the names the
// commands have used; new code includes detectors/sightings.hpp.

#include "detectors/sightings.hpp"

namespace lidarcal::pipeline {

using detectors::SightingOptions;
using detectors::toLandmarkObservations;

}  // namespace lidarcal::pipeline
