// SPDX-License-Identifier: BSD-3-Clause
#include "io/landmarks_csv.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "common/errors.hpp"

namespace lidarcal::io {

namespace {

constexpr const char* kHeader =
    "file,stop,landmark,bearing_rad,range_m,centre_x_m,centre_y_m,radius_m,n_points,rms_m";
constexpr const char* kRemedy = "see docs/FORMAT.md (landmarks.csv)";

/// RFC 4180 quoting when the field needs it.
std::string quoted(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + "\"";
}

/// Splits one CSV line (RFC 4180 quotes, no embedded newlines). Returns false on a bad quote.
bool splitCsv(const std::string& line, std::vector<std::string>& fields) {
  fields.assign(1, std::string());
  bool in_quotes = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (in_quotes) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"')
        fields.back() += '"', ++i;
      else if (c == '"')
        in_quotes = false;
      else
        fields.back() += c;
    } else if (c == '"' && fields.back().empty()) {
      in_quotes = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return !in_quotes;
}

}  // namespace

const char* landmarksCsvHeader() { return kHeader; }

LandmarksCsvWriter::LandmarksCsvWriter(const std::filesystem::path& file)
    : file_(file), out_(file, std::ios::trunc) {
  if (!out_)
    throw InputError(file.string(), "", "cannot be created",
                     "check that the directory is writable");
  out_ << kHeader << '\n';
}

void LandmarksCsvWriter::write(const LandmarkRow& r) {
  char line[320];
  std::snprintf(line, sizeof line, ",%zu,%d,%.9f,%.9f,%.9f,%.9f,%.9f,%zu,%.9f\n", r.stop,
                r.landmark, r.bearing_rad, r.range_m, r.centre_x_m, r.centre_y_m, r.radius_m,
                r.n_points, r.rms_m);
  out_ << quoted(r.file) << line;
}

void LandmarksCsvWriter::close() {
  out_.close();
  if (!out_)
    throw InputError(file_.string(), "", "write failed (disk full?)",
                     "free some space and run again");
}

std::vector<LandmarkRow> readLandmarksCsv(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in)
    throw InputError(file.string(), "", "cannot be opened",
                     "it is written by `lidarcal detect` into its --out directory");
  std::string line;
  if (!std::getline(in, line) || line != kHeader)
    throw InputError(file.string(), "line 1", std::string("header must be `") + kHeader + "`",
                     kRemedy);
  std::vector<LandmarkRow> rows;
  std::vector<std::string> f;
  static const char* const names[] = {"file",     "stop",       "landmark",   "bearing_rad",
                                      "range_m",  "centre_x_m", "centre_y_m", "radius_m",
                                      "n_points", "rms_m"};
  for (std::size_t line_no = 2; std::getline(in, line); ++line_no) {
    if (line.empty()) continue;
    const std::string where = "line " + std::to_string(line_no);
    if (!splitCsv(line, f)) throw InputError(file.string(), where, "unbalanced quotes", kRemedy);
    if (f.size() != 10)
      throw InputError(file.string(), where, "expected 10 comma-separated values", kRemedy);
    auto number = [&](std::size_t k) {
      char* end = nullptr;
      errno = 0;
      const double v = std::strtod(f[k].c_str(), &end);
      if (f[k].empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
        throw InputError(file.string(), where + ", column " + names[k],
                         "`" + f[k] + "` is not a finite number", kRemedy);
      return v;
    };
    auto count = [&](std::size_t k, double min) {
      const double v = number(k);
      if (v != std::floor(v) || v < min || v > 9.0e15)
        throw InputError(
            file.string(), where + ", column " + names[k],
            "`" + f[k] + "` is not an integer >= " + std::to_string(static_cast<int>(min)),
            kRemedy);
      return v;
    };
    LandmarkRow r;
    r.file = f[0];
    if (r.file.empty())
      throw InputError(file.string(), where + ", column file", "is empty", kRemedy);
    r.stop = static_cast<std::size_t>(count(1, 0));
    const double id = count(2, 1);
    if (id > 2147483647.0)
      throw InputError(file.string(), where + ", column landmark", "id too large", kRemedy);
    r.landmark = static_cast<int>(id);
    r.bearing_rad = number(3);
    r.range_m = number(4);
    r.centre_x_m = number(5);
    r.centre_y_m = number(6);
    r.radius_m = number(7);
    r.n_points = static_cast<std::size_t>(count(8, 0));
    r.rms_m = number(9);
    if (r.range_m < 0.0 || r.radius_m < 0.0 || r.rms_m < 0.0)
      throw InputError(file.string(), where, "range_m, radius_m and rms_m must be >= 0", kRemedy);
    rows.push_back(std::move(r));
  }
  return rows;
}

}  // namespace lidarcal::io
