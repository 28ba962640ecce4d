// SPDX-License-Identifier: BSD-3-Clause
// What `calibrate` prints for a rig: the lines to paste into a launch file or URDF carry a caution
// right above them when a range model was refused, with how far each mounting lies from its
// design (pipeline/reports/rig_report.hpp).

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "pipeline/reports/rig_report.hpp"

namespace lidarcal::test {
namespace {

/// Two sensors: `front` held at its design, `back` 130 mm forward and 163 mm left of its design
/// and turned by -1.61 deg (208 mm in all); each range model ok unless refused.
io::RigModel twoSensors(bool refuse_front, bool refuse_back) {
  io::RigModel m;
  m.frame = "relative";
  m.reference = "front";
  m.vehicle_frame = "base_footprint";
  for (const char* name : {"front", "back"}) {
    io::RigModelSensor s;
    s.name = name;
    s.frame_id = std::string(name) + "_lidar";
    const bool front = s.name == "front";
    s.design = Mounting{};
    s.design->x_m = front ? 1.5 : 0.8;
    s.design->y_m = front ? 0.35 : -0.45;
    s.design->yaw_rad = front ? 0.7 : -1.96;
    s.mounting = *s.design;
    s.mounting_held = front;
    if (!front) {
      s.mounting.x_m += 0.130;
      s.mounting.y_m += 0.163;
      s.mounting.yaw_rad += -1.61 * M_PI / 180.0;
    }
    if (front ? refuse_front : refuse_back)
      s.model.status = Status{StatusCode::not_identifiable, "trades off against the mounting"};
    m.sensors.push_back(s);
  }
  return m;
}

TEST(RigSnippets, ARefusedRangeModelPutsACautionRightAboveTheLinesToPaste) {
  for (const auto& [front, back] : {std::pair{true, true}, {false, true}, {true, false}}) {
    SCOPED_TRACE(std::to_string(front) + std::to_string(back));
    const std::string text = pipeline::rigSnippets(twoSensors(front, back));
    const std::size_t caution = text.find(
        "caution: these mountings rest on range models that "
        "were refused (");
    ASSERT_NE(caution, std::string::npos) << text;
    // right above the first line to paste
    EXPECT_EQ(text.find('\n', caution) + 1, text.find("rosrun tf2_ros")) << text;
    const std::string refused = front && back ? "front and back" : front ? "front" : "back";
    EXPECT_NE(text.find("refused (" + refused + ":"), std::string::npos) << text;
    EXPECT_NE(text.find("front is held at its design"), std::string::npos) << text;
    // hypot(130, 163) = 208.5 mm
    EXPECT_NE(text.find("back lies 208 mm from its design (x +130 mm, y +163 mm, yaw -1.61 deg)"),
              std::string::npos)
        << text;
  }
}

TEST(RigSnippets, DeterminedRangeModelsNeedNoCaution) {
  const std::string text = pipeline::rigSnippets(twoSensors(false, false));
  EXPECT_EQ(text.find("caution"), std::string::npos) << text;
  EXPECT_NE(text.find("rosrun tf2_ros static_transform_publisher"), std::string::npos) << text;
}

}  // namespace
}  // namespace lidarcal::test
