// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Checked access to JSON input files: every error names the file and the field path
// (e.g. `scene.json: sensor.range.bias.alpha[2]: must be a number`). io-internal.

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace lidarcal::io {

/// The whole content of an input file; throws InputError when it does not exist or cannot be
/// opened.
std::string readWholeFile(const std::filesystem::path& file);

/// Parses a JSON file; throws InputError with the line and column of a syntax error.
nlohmann::json readJsonFile(const std::filesystem::path& file);

/// A read-only view of one JSON object or value, remembering the file and its field path.
class JsonView {
 public:
  JsonView(std::string file, const nlohmann::json& value, std::string path = {});

  void requireObject() const;
  bool has(const std::string& key) const;
  JsonView child(const std::string& key) const;               ///< required object member
  std::vector<JsonView> array(const std::string& key) const;  ///< required array member
  std::vector<JsonView> elements() const;                     ///< this value as an array

  double getNumber(const std::string& key) const;
  double getNumber(const std::string& key, double fallback) const;
  double getPositive(const std::string& key) const;
  double getPositive(const std::string& key, double fallback) const;
  double getNonNegative(const std::string& key) const;
  double getNonNegative(const std::string& key, double fallback) const;
  int getInt(const std::string& key) const;
  int getInt(const std::string& key, int fallback) const;
  int getPositiveInt(const std::string& key) const;
  int getPositiveInt(const std::string& key, int fallback) const;
  std::string getString(const std::string& key) const;
  std::string getString(const std::string& key, const std::string& fallback) const;
  bool getBool(const std::string& key, bool fallback) const;
  std::vector<double> getNumbers(const std::string& key) const;
  double asNumber() const;

  /// Throws InputError for member `key` (empty: this value) with `problem`.
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const;
  const std::string& file() const { return file_; }
  std::string pathOf(const std::string& key) const;
  const nlohmann::json& json() const { return *value_; }

 private:
  const nlohmann::json& member(const std::string& key) const;
  std::string file_;
  const nlohmann::json* value_;
  std::string path_;
};

}  // namespace lidarcal::io
