// SPDX-License-Identifier: BSD-3-Clause
#include "io/model_yaml.hpp"

#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;

constexpr const char* kFormat = "lidarcal-ros-params/1";
constexpr const char* kRemedy = "write it again with `lidarcal export MODEL.json --format yaml`";

std::string readText(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw InputError(file.string(), "", "cannot be opened for reading",
                     "check the path and its permissions");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The value of a `key: value  # comment` line, comment removed (not inside a JSON string).
std::string valueOf(const std::string& rest) {
  bool quoted = false;
  std::size_t end = rest.size();
  for (std::size_t i = 0; i < rest.size(); ++i) {
    if (rest[i] == '"' && (i == 0 || rest[i - 1] != '\\')) quoted = !quoted;
    if (rest[i] == '#' && !quoted) {
      end = i;
      break;
    }
  }
  const std::string v = rest.substr(0, end);
  const auto a = v.find_first_not_of(" \t"), b = v.find_last_not_of(" \t\r");
  return a == std::string::npos ? "" : v.substr(a, b + 1 - a);
}

class Entries {
 public:
  Entries(const std::string& text, std::string file) : file_(std::move(file)) {
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#' || line[0] == ' ') continue;
      const auto colon = line.find(':');
      if (colon != std::string::npos)
        values_[line.substr(0, colon)] = valueOf(line.substr(colon + 1));
    }
  }
  const std::string& raw(const std::string& key) const {
    const auto it = values_.find(key);
    if (it == values_.end()) fail(key, "is missing");
    return it->second;
  }
  /// A YAML scalar read as JSON (numbers, lists, JSON strings); YAML's .nan (export's text for a
  /// number that is not finite) becomes null.
  nlohmann::json json(const std::string& key) const {
    std::string v = raw(key);
    for (auto at = v.find(".nan"); at != std::string::npos; at = v.find(".nan", at))
      v.replace(at, 4, "null");
    try {
      return nlohmann::json::parse(v);
    } catch (const nlohmann::json::exception&) {
      fail(key, "'" + raw(key) + "' is not a number, a list of numbers or a quoted string");
    }
  }
  double number(const std::string& key) const {
    const nlohmann::json j = json(key);
    if (j.is_null()) return std::numeric_limits<double>::quiet_NaN();
    if (!j.is_number()) fail(key, "is not a number");
    return j.get<double>();
  }
  std::vector<double> numbers(const std::string& key, std::size_t min_size) const {
    const nlohmann::json j = json(key);
    if (!j.is_array() || j.size() < min_size)
      fail(key, "is not a list of at least " + std::to_string(min_size) + " numbers");
    std::vector<double> out;
    for (const auto& x : j) {
      if (!x.is_number()) fail(key, "holds something that is not a number");
      out.push_back(x.get<double>());
    }
    return out;
  }
  std::string text(const std::string& key) const {
    const std::string& v = raw(key);
    if (v.empty() || v[0] != '"') return v;  // plain scalars (ls, keep) stay as written
    const nlohmann::json j = json(key);
    if (!j.is_string()) fail(key, "is not a string");
    return j.get<std::string>();
  }
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw InputError(file_, key, problem, kRemedy);
  }

 private:
  std::string file_;
  std::map<std::string, std::string> values_;
};

nlohmann::json parseOrText(const std::string& v) {
  try {
    return nlohmann::json::parse(v);
  } catch (const nlohmann::json::exception&) {
    return v;
  }
}

}  // namespace

bool isExportedModelYaml(const fs::path& file) {
  std::istringstream in(readText(file));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    // export's first key is format; a model.json starts with '{'.
    return line.rfind("format:", 0) == 0 && parseOrText(valueOf(line.substr(7))) == kFormat;
  }
  return false;
}

ExportedModel readExportedModelYaml(const fs::path& file) {
  const Entries e(readText(file), file.string());
  if (e.text("format") != kFormat)
    e.fail("format", "is '" + e.raw("format") + "', not \"" + kFormat + "\"");
  ExportedModel out;
  CalibrationModel& m = out.model;
  m.method = "export";
  m.sensor_name = e.text("sensor_name");
  const double beams = e.number("beams");
  if (!(beams >= 0) || beams != static_cast<int>(beams))
    e.fail("beams", "is not a whole number of beams (0: not recorded)");
  if (beams > 0) m.beams = static_cast<int>(beams);
  m.model.bias.alpha = e.numbers("bias_alpha", 2);
  const std::vector<double> valid = e.numbers("valid_range_m", 2);
  if (!(valid[0] < valid[1])) e.fail("valid_range_m", "is not [smaller, larger] distances");
  m.fitted_range_m = std::make_pair(valid[0], valid[1]);
  m.model.range_min_m = e.number("range_min_m");
  m.model.range_max_m = e.number("range_max_m");
  if (!parseNoiseKind(e.text("noise_law"), m.model.noise.kind))
    e.fail("noise_law", "is not a noise law lidarcal knows");
  m.model.noise.sigma_e = e.number("noise_sigma_e");
  out.inversion = e.text("inversion");
  out.outside = e.text("outside");
  return out;
}

}  // namespace lidarcal::io
