// SPDX-License-Identifier: BSD-3-Clause
#include "io/json_util.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "common/errors.hpp"

namespace lidarcal::io {

namespace {
constexpr const char* kRemedy = "see docs/FORMAT.md";
}

std::string readWholeFile(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    std::error_code ec;
    if (!std::filesystem::exists(file, ec))
      throw InputError(file.string(), "", "file does not exist", "check the path");
    throw InputError(file.string(), "", "cannot be opened for reading", "check its permissions");
  }
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

nlohmann::json readJsonFile(const std::filesystem::path& file) {
  const std::string text = readWholeFile(file);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // Translate the byte offset into line and column.
    std::size_t line = 1, col = 1;
    for (std::size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
      if (text[i] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    throw InputError(file.string(),
                     "line " + std::to_string(line) + " column " + std::to_string(col),
                     "not valid JSON", "fix the syntax; the file must be one JSON object");
  }
}

JsonView::JsonView(std::string file, const nlohmann::json& value, std::string path)
    : file_(std::move(file)), value_(&value), path_(std::move(path)) {}

std::string JsonView::pathOf(const std::string& key) const {
  if (key.empty()) return path_.empty() ? std::string("(top level)") : path_;
  if (path_.empty()) return key;
  return key[0] == '[' ? path_ + key : path_ + "." + key;
}

void JsonView::fail(const std::string& key, const std::string& problem) const {
  throw InputError(file_, pathOf(key), problem, kRemedy);
}

void JsonView::requireObject() const {
  if (!value_->is_object()) fail("", "must be a JSON object");
}

bool JsonView::has(const std::string& key) const {
  return value_->is_object() && value_->contains(key);
}

const nlohmann::json& JsonView::member(const std::string& key) const {
  requireObject();
  auto it = value_->find(key);
  if (it == value_->end()) fail(key, "missing");
  return *it;
}

JsonView JsonView::child(const std::string& key) const {
  JsonView v(file_, member(key), pathOf(key));
  v.requireObject();
  return v;
}

std::vector<JsonView> JsonView::array(const std::string& key) const {
  return JsonView(file_, member(key), pathOf(key)).elements();
}

std::vector<JsonView> JsonView::elements() const {
  if (!value_->is_array()) fail("", "must be an array");
  std::vector<JsonView> out;
  out.reserve(value_->size());
  for (std::size_t i = 0; i < value_->size(); ++i)
    out.emplace_back(file_, (*value_)[i], pathOf("[" + std::to_string(i) + "]"));
  return out;
}

double JsonView::asNumber() const {
  if (!value_->is_number()) fail("", "must be a number");
  const double v = value_->get<double>();
  if (!std::isfinite(v)) fail("", "must be finite");
  return v;
}

double JsonView::getNumber(const std::string& key) const {
  return JsonView(file_, member(key), pathOf(key)).asNumber();
}
double JsonView::getNumber(const std::string& key, double fallback) const {
  return has(key) ? getNumber(key) : fallback;
}

double JsonView::getPositive(const std::string& key) const {
  const double v = getNumber(key);
  if (!(v > 0.0)) fail(key, "must be positive");
  return v;
}
double JsonView::getPositive(const std::string& key, double fallback) const {
  return has(key) ? getPositive(key) : fallback;
}

double JsonView::getNonNegative(const std::string& key) const {
  const double v = getNumber(key);
  if (v < 0.0) fail(key, "must not be negative");
  return v;
}
double JsonView::getNonNegative(const std::string& key, double fallback) const {
  return has(key) ? getNonNegative(key) : fallback;
}

int JsonView::getInt(const std::string& key) const {
  const auto& m = member(key);
  if (!m.is_number_integer()) fail(key, "must be an integer");
  const auto v = m.get<long long>();
  if (v < -2147483647LL || v > 2147483647LL) fail(key, "is out of range");
  return static_cast<int>(v);
}
int JsonView::getInt(const std::string& key, int fallback) const {
  return has(key) ? getInt(key) : fallback;
}

int JsonView::getPositiveInt(const std::string& key) const {
  const int v = getInt(key);
  if (v <= 0) fail(key, "must be a positive integer");
  return v;
}
int JsonView::getPositiveInt(const std::string& key, int fallback) const {
  return has(key) ? getPositiveInt(key) : fallback;
}

std::string JsonView::getString(const std::string& key) const {
  const auto& m = member(key);
  if (!m.is_string()) fail(key, "must be a string");
  return m.get<std::string>();
}
std::string JsonView::getString(const std::string& key, const std::string& fallback) const {
  return has(key) ? getString(key) : fallback;
}

bool JsonView::getBool(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const auto& m = member(key);
  if (!m.is_boolean()) fail(key, "must be true or false");
  return m.get<bool>();
}

std::vector<double> JsonView::getNumbers(const std::string& key) const {
  std::vector<double> out;
  for (const auto& e : array(key)) out.push_back(e.asNumber());
  return out;
}

}  // namespace lidarcal::io
