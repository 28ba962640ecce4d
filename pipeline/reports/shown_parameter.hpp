// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How a command's table shows a parameter: its label, the unit and the factor from SI.

namespace lidarcal::pipeline {

struct ShownParameter {
  const char* label;
  const char* unit;
  double scale;
};

}  // namespace lidarcal::pipeline
