// SPDX-License-Identifier: BSD-3-Clause
// Odometry tuples: objects read one after another whatever the lines, and bad input refused
// with the file, the object (number and line) and the field named.

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "io/odometry_tuples.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::TempDir;
using test::writeFile;

const std::string kFirst =
    R"({ "T": 0.8, "phi_l": 0.5, "phi_r": -0.25, "sm": [ 0.001, -0.002, -0.18 ] })";
const std::string kSecond = R"({"T":1.0,"phi_l":0.0,"phi_r":0.1,"sm":[1e-3,0,0.01]})";

TEST(OdometryTuples, ReadsObjectsNotLines) {
  TempDir dir;
  // Two objects on line 1, one spanning lines 2-4, one after a blank line.
  writeFile(dir / "t.tuple", kFirst + kSecond + "\n{\"T\": 0.5,\n \"phi_l\": 1,\n \"phi_r\": 2, " +
                                 "\"sm\": [0, 0, 0]}\n\n" + kFirst);
  const std::vector<OdometrySample> s = readOdometryTuples(dir / "t.tuple");
  ASSERT_EQ(s.size(), 4u);
  EXPECT_EQ(s[0].duration_s, 0.8);
  EXPECT_EQ(s[0].left_wheel_rad_s, 0.5);
  EXPECT_EQ(s[0].right_wheel_rad_s, -0.25);
  EXPECT_EQ(s[0].scan_match_x_m, 0.001);
  EXPECT_EQ(s[0].scan_match_y_m, -0.002);
  EXPECT_EQ(s[0].scan_match_theta_rad, -0.18);
  EXPECT_EQ(s[1].duration_s, 1.0);
  EXPECT_EQ(s[1].scan_match_theta_rad, 0.01);
  EXPECT_EQ(s[2].right_wheel_rad_s, 2.0);  // an integer is a number too
  EXPECT_EQ(s[3].left_wheel_rad_s, 0.5);
}

TEST(OdometryTuples, IgnoresFieldsItDoesNotKnow) {
  TempDir dir;
  writeFile(dir / "t.tuple", R"({"T":1,"phi_l":0,"phi_r":0,"sm":[0,0,0],"note":"x"})");
  EXPECT_EQ(readOdometryTuples(dir / "t.tuple").size(), 1u);
}

/// The message of the InputError reading `text` throws (empty if none).
std::string errorOf(const std::string& text) {
  TempDir dir;
  writeFile(dir / "bad.tuple", text);
  try {
    readOdometryTuples(dir / "bad.tuple");
  } catch (const InputError& e) {
    return e.what();
  }
  return {};
}

void expectParts(const std::string& message, const std::vector<std::string>& parts) {
  ASSERT_FALSE(message.empty()) << "no error";
  for (const std::string& part : parts)
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
}

TEST(OdometryTuples, ATruncatedFileNamesItsLastObject) {
  const std::string text = kFirst + "\n" + kFirst + "\n" + kFirst.substr(0, 30);
  expectParts(errorOf(text), {"bad.tuple", "object 3 (line 3)", "cut short"});
}

TEST(OdometryTuples, AMissingFieldIsNamed) {
  expectParts(errorOf(kFirst + "\n" + R"({"T": 0.8, "phi_l": 0.5, "sm": [0, 0, 0]})"),
              {"bad.tuple", "object 2 (line 2)", "field phi_r", "is missing", "FORMAT.md"});
  expectParts(errorOf(R"({"T": 0.8, "phi_l": 0.5, "phi_r": 0.5})"),
              {"object 1 (line 1)", "field sm", "is missing"});
}

TEST(OdometryTuples, ANonNumberIsNamed) {
  expectParts(
      errorOf(kSecond + kFirst + R"({"T": 0.8, "phi_l": "fast", "phi_r": 0, "sm": [0,0,0]})"),
      {"object 3 (line 1)", "field phi_l", "must be a number", "\"fast\""});
  expectParts(errorOf(R"({"T": 0.8, "phi_l": 0, "phi_r": 0, "sm": [0, null, 0]})"),
              {"object 1", "field sm[1]", "must be a number"});
  expectParts(errorOf(R"({"T": 0.8, "phi_l": 0, "phi_r": 0, "sm": [0, 0]})"),
              {"object 1", "field sm", "3 numbers"});
}

TEST(OdometryTuples, ANonPositiveIntervalIsRefused) {
  expectParts(errorOf(R"({"T": 0, "phi_l": 0, "phi_r": 0, "sm": [0, 0, 0]})"),
              {"object 1", "field T", "must be positive"});
  expectParts(errorOf(R"({"T": -0.8, "phi_l": 0, "phi_r": 0, "sm": [0, 0, 0]})"),
              {"field T", "must be positive"});
  expectParts(errorOf(R"({"T": 1e999, "phi_l": 0, "phi_r": 0, "sm": [0, 0, 0]})"),
              {"object 1 (line 1)", "out of range", "1e999"});
}

TEST(OdometryTuples, MalformedOrEmptyInputIsRefused) {
  expectParts(errorOf(kFirst + "\n{\"T\": 0.8,, }\n" + kFirst),
              {"object 2 (line 2)", "not valid JSON near line 2"});
  expectParts(errorOf("[1, 2, 3]"), {"object 1 (line 1)", "not a JSON object"});
  expectParts(errorOf(""), {"bad.tuple", "holds no tuple"});
  expectParts(errorOf("  \n\n "), {"holds no tuple"});
  try {
    readOdometryTuples("/nonexistent/odometry.tuple");
    FAIL() << "no error";
  } catch (const InputError& e) {
    expectParts(e.what(), {"odometry.tuple", "does not exist"});
  }
}

}  // namespace
}  // namespace lidarcal::io
