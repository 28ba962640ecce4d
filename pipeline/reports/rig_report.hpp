// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What `calibrate` makes of a rig's joint calibration: the rig model.json (io/rig_model_io.hpp)
// and the text that compares each mounting with its design (tf_static), with snippets to paste
// into a launch file or a URDF.

#include <string>

#include "calibration/rig_calibrate.hpp"
#include "io/rig.hpp"
#include "io/rig_model_io.hpp"

namespace lidarcal::pipeline {

/// The rig model of a successful calibration of `rig`.
io::RigModel rigModel(const io::Rig& rig, const calibration::RigResult& result);

/// Markdown: per sensor the mounting with standard errors, its design and the difference
/// (mm, deg, each with its standard error), the relative mountings against the design's, and
/// each range model.
std::string rigMountingTable(const io::RigModel& model);

/// `static_transform_publisher` arguments and URDF joints for the estimated mountings (the
/// vehicle frame as parent; in the relative frame, the reference held at its design). When a
/// sensor's range model was refused, a caution right above them says that the mountings rest on
/// it and how far each lies from its design.
std::string rigSnippets(const io::RigModel& model);

}  // namespace lidarcal::pipeline
