// SPDX-License-Identifier: BSD-3-Clause
#include "io/line_reader.hpp"

#include <algorithm>
#include <cstring>

#include <zlib.h>

#include "common/errors.hpp"

namespace lidarcal::io {
namespace fs = std::filesystem;

namespace {
gzFile handle(void* p) { return static_cast<gzFile>(p); }
constexpr int kBufferBytes = 1 << 16;
}  // namespace

LineReader::LineReader(const fs::path& file) : file_(file) {
  std::error_code ec;
  if (!fs::exists(file, ec))
    throw InputError(file.string(), "", "file does not exist", "check the path");
  if (fs::is_directory(file, ec))
    throw InputError(file.string(), "", "is a directory, expected a file", "pass the file itself");
  const auto bytes = fs::file_size(file, ec);
  file_bytes_ = ec ? 0 : static_cast<std::size_t>(bytes);
  gz_ = gzopen(file.c_str(), "rb");
  if (!gz_)
    throw InputError(file.string(), "", "cannot be opened for reading", "check its permissions");
  gzbuffer(handle(gz_), kBufferBytes);
  // gzdirect() is only meaningful after the first read has looked at the magic bytes.
  const int c = gzgetc(handle(gz_));
  if (c != -1) gzungetc(c, handle(gz_));
  compressed_ = gzdirect(handle(gz_)) == 0;
  int err = Z_OK;
  const char* msg = gzerror(handle(gz_), &err);
  if (err != Z_OK) {
    // The destructor does not run when the constructor throws: close here (found by fuzzing,
    // tests/fuzz/regressions/carmen/).
    const std::string text = msg;
    gzclose(handle(gz_));
    gz_ = nullptr;
    fail(text);
  }
}

LineReader::~LineReader() {
  if (gz_) gzclose(handle(gz_));
}

void LineReader::fail(const std::string& zlib_text) const {
  // zlib prefixes its messages with the path given to gzopen().
  std::string zlib_message = zlib_text;
  const std::string prefix = file_.string() + ": ";
  if (zlib_message.compare(0, prefix.size(), prefix) == 0) zlib_message.erase(0, prefix.size());
  const std::string item =
      line_number_ == 0 ? "start of file" : "after line " + std::to_string(line_number_);
  if (compressed_)
    throw InputError(
        file_.string(), item, "the gzip data is damaged or cut short (zlib: " + zlib_message + ")",
        "the file is corrupt: copy or download it again (`gzip -t FILE` checks a gzip file)");
  throw InputError(file_.string(), item, "read error (" + zlib_message + ")",
                   "check the file and the disk");
}

bool LineReader::next(std::string& line) {
  line.clear();
  char buffer[4096];
  bool got_any = false;
  for (;;) {
    char* p = gzgets(handle(gz_), buffer, sizeof buffer);
    int err = Z_OK;
    const char* msg = gzerror(handle(gz_), &err);
    if (err != Z_OK) fail(msg);
    if (!p) break;  // end of file
    got_any = true;
    const std::size_t len = std::strlen(buffer);
    if (len > 0 && buffer[len - 1] == '\n') {
      line.append(buffer, len - 1);
      break;
    }
    line.append(buffer, len);
  }
  if (!got_any) return false;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  ++line_number_;
  return true;
}

double LineReader::progress() const {
  if (file_bytes_ == 0) return 1.0;
  const z_off_t offset = gzoffset(handle(gz_));
  return offset < 0 ? 0.0
                    : std::min(1.0, static_cast<double>(offset) / static_cast<double>(file_bytes_));
}

}  // namespace lidarcal::io
