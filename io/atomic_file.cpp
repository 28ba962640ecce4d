// SPDX-License-Identifier: BSD-3-Clause
#include "io/atomic_file.hpp"

#include <unistd.h>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>

#include "common/errors.hpp"

namespace lidarcal::io {
namespace fs = std::filesystem;
namespace {

std::string uniqueSuffix() {
  static std::atomic<unsigned long> counter{0};
  return std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

fs::path normalised(const fs::path& p) {
  std::error_code ec;
  fs::path abs = fs::weakly_canonical(fs::absolute(p, ec), ec);
  return ec ? fs::absolute(p).lexically_normal() : abs;
}

}  // namespace

void writeAtomically(const fs::path& file, const std::function<void(const fs::path&)>& write) {
  const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(file.string(), "", dir.string() + " is a file, not a directory",
                     "choose a path in a directory");
  if (!fs::is_directory(dir, ec))
    throw InputError(file.string(), "", "the directory to write into does not exist",
                     "create it first");
  // Never replace a directory, a device (/dev/null, /dev/full) or another special file by a
  // rename: only a regular file may be overwritten.
  const fs::file_status st = fs::symlink_status(file, ec);
  if (fs::exists(st) && !fs::is_regular_file(st))
    throw InputError(file.string(), "",
                     fs::is_directory(st) ? "is a directory, expected a file name"
                                          : "exists and is not a regular file",
                     "choose the path of a (new or regular) file to write");
  const fs::path tmp = dir / ("." + file.filename().string() + ".tmp-" + uniqueSuffix());
  try {
    write(tmp);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, file, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError(file.string(), "", "could not move the finished file into place",
                     "check permissions");
  }
}

void writeTextAtomically(const fs::path& file, const std::string& bytes) {
  writeAtomically(file, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      throw InputError(file.string(), "", "cannot be created",
                       "check that the directory is writable");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out)
      throw InputError(file.string(), "", "write failed (disk full?)",
                       "free some space and run again");
  });
}

void checkOutsideInput(const fs::path& input, const fs::path& out) {
  const fs::path in_abs = normalised(input);
  const fs::path out_abs = normalised(out);
  auto in_it = in_abs.begin();
  auto out_it = out_abs.begin();
  for (; in_it != in_abs.end() && out_it != out_abs.end(); ++in_it, ++out_it)
    if (*in_it != *out_it) return;
  if (in_it == in_abs.end() || (in_it->empty() && std::next(in_it) == in_abs.end()))
    throw InputError(out.string(), "--out", "is the input or inside it (" + input.string() + ")",
                     "choose an output path outside the input; inputs are never modified");
}

void checkOutputFile(const fs::path& file, bool overwrite) {
  std::error_code ec;
  const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(file.string(), "--out", dir.string() + " is a file, not a directory",
                     "choose a path in a directory");
  if (!fs::is_directory(dir, ec))
    throw InputError(file.string(), "--out", "its directory does not exist",
                     "create " + dir.string() + " first");
  const fs::file_status st = fs::symlink_status(file, ec);
  if (fs::is_directory(st))
    throw InputError(file.string(), "--out", "is a directory, expected a file name",
                     "give the path of the file to write");
  if (fs::exists(st) && !fs::is_regular_file(st))
    throw InputError(file.string(), "--out", "exists and is not a regular file",
                     "give the path of a new file");
  if (fs::exists(st) && !overwrite)
    throw InputError(file.string(), "--out", "already exists",
                     "choose another file or pass --overwrite");
  // Fail now rather than after the work: can a file be created there?
  const fs::path probe = dir / ("." + file.filename().string() + ".probe-" + uniqueSuffix());
  {
    std::ofstream out(probe, std::ios::binary);
    if (!out)
      throw InputError(file.string(), "--out",
                       "cannot be created (" + std::string(std::strerror(errno)) + ")",
                       "check that " + dir.string() + " is writable");
  }
  fs::remove(probe, ec);
}

StagedDirectory::StagedDirectory(fs::path out, bool overwrite)
    : out_(std::move(out)), overwrite_(overwrite) {
  if (out_.filename().empty()) out_ = out_.parent_path();  // "dir/" -> "dir"
  std::error_code ec;
  const fs::path parent = out_.has_parent_path() ? out_.parent_path() : fs::path(".");
  if (fs::exists(parent, ec) && !fs::is_directory(parent, ec))
    throw InputError(out_.string(), "--out", parent.string() + " is a file, not a directory",
                     "choose an output path in a directory");
  if (!fs::is_directory(parent, ec))
    throw InputError(out_.string(), "--out", "its parent directory does not exist",
                     "create " + parent.string() + " first");
  if (fs::exists(out_, ec) && !fs::is_directory(out_, ec))
    throw InputError(out_.string(), "--out", "is a file; the output is a directory",
                     "choose a new path (lidarcal does not replace a file by a directory, even "
                     "with --overwrite)");
  if (fs::exists(out_, ec) && !overwrite_) {
    const bool empty_dir = fs::is_directory(out_, ec) && fs::is_empty(out_, ec);
    if (!empty_dir)
      throw InputError(out_.string(), "--out", "already exists and is not empty",
                       "choose a new path or pass --overwrite to replace it");
  }
  staging_ = parent / ("." + out_.filename().string() + ".partial-" + uniqueSuffix());
  fs::create_directory(staging_, ec);
  if (ec)
    throw InputError(out_.string(), "--out",
                     "cannot create the output directory (" + ec.message() + ")",
                     "check that " + parent.string() + " is writable");
}

StagedDirectory::~StagedDirectory() {
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(staging_, ec);
  }
}

void StagedDirectory::commit() {
  std::error_code ec;
  fs::path old;
  if (fs::exists(out_, ec)) {
    old = out_.parent_path() / ("." + out_.filename().string() + ".old-" + uniqueSuffix());
    fs::rename(out_, old, ec);
    if (ec)
      throw InputError(out_.string(), "--out", "could not move the existing output aside",
                       "check permissions");
  }
  fs::rename(staging_, out_, ec);
  if (ec) {
    if (!old.empty()) fs::rename(old, out_, ec);
    throw InputError(out_.string(), "--out", "could not move the finished output into place",
                     "check permissions");
  }
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, ec);
}

}  // namespace lidarcal::io
