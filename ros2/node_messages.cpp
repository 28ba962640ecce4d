// SPDX-License-Identifier: BSD-3-Clause
#include "ros2/node_messages.hpp"

#include <chrono>
#include <cmath>

namespace lidarcal::ros2 {

RosTime wallClockNow() {
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                      std::chrono::system_clock::now().time_since_epoch())
                      .count();
  RosTime t;
  t.sec = static_cast<std::int32_t>(ns / 1000000000);
  t.nanosec = static_cast<std::uint32_t>(ns % 1000000000);
  return t;
}

RosTime rosTimeFromSeconds(double seconds) {
  double whole = std::floor(seconds);
  double nanos = std::round((seconds - whole) * 1e9);
  if (nanos >= 1e9) {  // rounded up to the next second
    whole += 1.0;
    nanos = 0.0;
  }
  RosTime t;
  t.sec = static_cast<std::int32_t>(whole);
  t.nanosec = static_cast<std::uint32_t>(nanos);
  return t;
}

}  // namespace lidarcal::ros2
