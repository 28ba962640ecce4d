// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Small helpers for printed text.

#include "common/plural.hpp"

namespace lidarcal::pipeline {

using lidarcal::plural;  // common/plural.hpp: "1 stop", "2 stops"

}  // namespace lidarcal::pipeline
