// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Line-by-line reading of a text file that may be gzip-compressed (zlib detects gzip by its
// magic bytes and reads plain files as they are). Holds one line in memory. Decompression
// errors (corrupt or truncated gzip) are InputErrors naming the file and the line.

#include <cstddef>
#include <filesystem>
#include <string>

namespace lidarcal::io {

class LineReader {
 public:
  /// Opens `file`. Throws InputError when it does not exist or cannot be read.
  explicit LineReader(const std::filesystem::path& file);
  ~LineReader();
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  /// Reads the next line (without the line break, and without a trailing '\r') into `line`.
  /// Returns false at the end of the file. Throws InputError on a read or decompression error.
  bool next(std::string& line);

  /// 1-based number of the line last returned by next().
  std::size_t lineNumber() const { return line_number_; }
  /// Fraction of the (compressed) file consumed, 0..1.
  double progress() const;
  /// True when the file is gzip-compressed.
  bool compressed() const { return compressed_; }
  const std::filesystem::path& file() const { return file_; }

 private:
  [[noreturn]] void fail(const std::string& zlib_message) const;
  std::filesystem::path file_;
  void* gz_ = nullptr;  // gzFile, kept opaque so that zlib.h stays out of this header
  std::size_t line_number_ = 0;
  std::size_t file_bytes_ = 0;
  bool compressed_ = false;
};

}  // namespace lidarcal::io
