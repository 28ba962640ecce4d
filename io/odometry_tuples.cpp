// SPDX-License-Identifier: BSD-3-Clause
#include "io/odometry_tuples.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/json_util.hpp"

namespace lidarcal::io {
namespace {

constexpr const char* kRemedy =
    "each tuple is {\"T\": s, \"phi_l\": rad/s, \"phi_r\": rad/s, \"sm\": [x, y, theta]}, "
    "docs/FORMAT.md";

/// One object of the file being read: names it in errors as "object N (line L)".
struct TupleView {
  const std::string& file;
  const nlohmann::json& value;
  std::string name;

  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw InputError(file, field.empty() ? name : name + ", field " + field, problem, kRemedy);
  }
  double number(const nlohmann::json& v, const std::string& field) const {
    if (!v.is_number()) fail(field, "must be a number, found " + v.dump().substr(0, 40));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(field, "must be a finite number");
    return x;
  }
  double field(const char* key) const {
    const auto it = value.find(key);
    if (it == value.end()) fail(key, "is missing");
    return number(*it, key);
  }
};

OdometrySample readTuple(const TupleView& t) {
  if (!t.value.is_object()) t.fail("", "is not a JSON object");
  OdometrySample s;
  s.duration_s = t.field("T");
  if (!(s.duration_s > 0.0)) t.fail("T", "must be positive (the interval's length, seconds)");
  s.left_wheel_rad_s = t.field("phi_l");
  s.right_wheel_rad_s = t.field("phi_r");
  const auto sm = t.value.find("sm");
  if (sm == t.value.end()) t.fail("sm", "is missing");
  if (!sm->is_array() || sm->size() != 3)
    t.fail("sm", "must be an array of 3 numbers [x m, y m, theta rad]");
  s.scan_match_x_m = t.number((*sm)[0], "sm[0]");
  s.scan_match_y_m = t.number((*sm)[1], "sm[1]");
  s.scan_match_theta_rad = t.number((*sm)[2], "sm[2]");
  return s;
}

std::size_t newlinesBetween(const std::string& text, std::size_t from, std::size_t to) {
  return static_cast<std::size_t>(std::count(text.begin() + static_cast<std::ptrdiff_t>(from),
                                             text.begin() + static_cast<std::ptrdiff_t>(to), '\n'));
}

}  // namespace

std::vector<OdometrySample> readOdometryTuples(const std::filesystem::path& file) {
  // Read whole (a tuple is ~120 bytes: an hour of 0.8 s intervals is half a megabyte), so that
  // errors can name the line an object starts on.
  const std::string text = readWholeFile(file);
  const std::string name = file.string();
  std::istringstream in(text);
  std::vector<OdometrySample> samples;
  std::size_t line = 1, counted_to = 0;
  for (std::size_t object = 1;; ++object) {
    while (in.peek() != std::char_traits<char>::eof() && std::isspace(in.peek())) in.get();
    if (in.peek() == std::char_traits<char>::eof()) break;
    const auto start = static_cast<std::size_t>(in.tellg());
    line += newlinesBetween(text, counted_to, start);
    counted_to = start;
    const std::string label =
        "object " + std::to_string(object) + " (line " + std::to_string(line) + ")";
    nlohmann::json value;
    try {
      in >> value;
    } catch (const nlohmann::json::parse_error& e) {
      const std::size_t at = std::min(text.size(), start + (e.byte > 0 ? e.byte - 1 : 0));
      const bool cut = at >= text.size() || in.eof();
      throw InputError(
          name, label,
          cut ? "cut short: the file ends inside this object"
              : "not valid JSON near line " +
                    std::to_string(line + newlinesBetween(text, start, at)),
          cut ? "the recording was cut short: remove the partial object at the end" : kRemedy);
    } catch (const nlohmann::json::exception& e) {  // a number beyond a double's range
      const std::string what = e.what();  // "[json.exception.out_of_range.406] number overflow ..."
      throw InputError(
          name, label,
          "holds a number out of range for a double (" + what.substr(what.find(']') + 2) + ")",
          kRemedy);
    }
    samples.push_back(readTuple(TupleView{name, value, label}));
  }
  if (samples.empty()) throw InputError(name, "", "holds no tuple (no JSON object)", kRemedy);
  return samples;
}

}  // namespace lidarcal::io
