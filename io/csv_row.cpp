// SPDX-License-Identifier: BSD-3-Clause
#include "io/csv_row.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "common/errors.hpp"

namespace lidarcal::io {

std::vector<std::string> splitCsvLine(const std::string& line) {
  std::string s = line;
  if (!s.empty() && s.back() == '\r') s.pop_back();
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = s.find(',', start);
    fields.push_back(
        s.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

CsvReader::CsvReader(const std::filesystem::path& file, std::string remedy)
    : file_(file), remedy_(std::move(remedy)), in_(file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec))
    throw InputError(file.string(), "", "file does not exist", remedy_);
  if (!in_) throw InputError(file.string(), "", "cannot be opened", "check its permissions");
}

std::vector<std::string> CsvReader::readHeader() {
  std::string line;
  if (!std::getline(in_, line))
    throw InputError(file_.string(), "line 1", "file is empty (no header)", remedy_);
  line_no_ = 1;
  return splitCsvLine(line);
}

void CsvReader::expectHeader(const std::string& expected) {
  const auto names = readHeader();
  if (names != splitCsvLine(expected))
    throw InputError(file_.string(), "line 1", "header must be `" + expected + "`", remedy_);
}

bool CsvReader::next(std::size_t columns) {
  std::string line;
  while (std::getline(in_, line)) {
    ++line_no_;
    if (line.empty() || line == "\r") continue;
    fields_ = splitCsvLine(line);
    if (fields_.size() != columns)
      throw InputError(file_.string(), "line " + std::to_string(line_no_),
                       "expected " + std::to_string(columns) + " comma-separated values, found " +
                           std::to_string(fields_.size()),
                       remedy_);
    return true;
  }
  return false;
}

void CsvReader::fail(const std::string& name, const std::string& problem) const {
  throw InputError(file_.string(), "line " + std::to_string(line_no_) + ", column " + name, problem,
                   remedy_);
}

double CsvReader::number(std::size_t index, const std::string& name) const {
  const std::string& f = fields_.at(index);
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(f.c_str(), &end);
  if (f.empty() || end != f.c_str() + f.size()) fail(name, "`" + f + "` is not a number");
  if (!std::isfinite(v) || errno == ERANGE) fail(name, "`" + f + "` is not a finite number");
  return v;
}

long long CsvReader::integer(std::size_t index, const std::string& name) const {
  const std::string& f = fields_.at(index);
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(f.c_str(), &end, 10);
  if (f.empty() || end != f.c_str() + f.size() || errno == ERANGE)
    fail(name, "`" + f + "` is not an integer");
  return v;
}

}  // namespace lidarcal::io
