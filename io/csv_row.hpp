// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Checked reading of simple CSV files (no quoting): a header line, then rows of fields.
// Every error names the file, the line, the column and what to do. io-internal.

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace lidarcal::io {

/// Reads a CSV file line by line, checking the header and giving typed, checked fields.
class CsvReader {
 public:
  /// Opens `file`; throws InputError when it is missing or cannot be opened. `remedy` ends
  /// every message (e.g. where such a file comes from, which page documents it).
  CsvReader(const std::filesystem::path& file, std::string remedy);

  /// Reads the header and checks it is exactly `expected` (comma-separated names).
  void expectHeader(const std::string& expected);
  /// Reads the header and returns its column names (for files whose column order may vary).
  std::vector<std::string> readHeader();

  /// Reads the next non-empty row; returns false at the end of the file. Throws InputError
  /// when the row does not have `columns` fields.
  bool next(std::size_t columns);

  /// Field `index` of the current row as a finite number / integer; `name` is the column name
  /// used in messages.
  double number(std::size_t index, const std::string& name) const;
  long long integer(std::size_t index, const std::string& name) const;
  const std::string& text(std::size_t index) const { return fields_.at(index); }

  /// Throws InputError for the current line and column `name` with `problem`.
  [[noreturn]] void fail(const std::string& name, const std::string& problem) const;

  std::size_t line() const { return line_no_; }
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
  std::string remedy_;
  std::ifstream in_;
  std::size_t line_no_ = 0;
  std::vector<std::string> fields_;
};

/// Splits one CSV line at commas (no quoting; a trailing '\r' is dropped).
std::vector<std::string> splitCsvLine(const std::string& line);

}  // namespace lidarcal::io
