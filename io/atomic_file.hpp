// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Outputs are written atomically: a file appears complete or not at all; an output directory
// is filled under a staging name and renamed into place when it is complete.

#include <filesystem>
#include <functional>
#include <string>

namespace lidarcal::io {

/// Calls write(tmp) with a temporary path next to `file`, then renames tmp onto `file`.
/// The temporary file is removed if write throws.
void writeAtomically(const std::filesystem::path& file,
                     const std::function<void(const std::filesystem::path&)>& write);

/// Writes `bytes` to `file` atomically.
void writeTextAtomically(const std::filesystem::path& file, const std::string& bytes);

/// Checks an output file path before any work is done: its directory exists, it is not a
/// directory or a special file, and it does not exist unless `overwrite`. Throws InputError
/// naming --out.
void checkOutputFile(const std::filesystem::path& file, bool overwrite);

/// Throws InputError when `out` is `input` or lies inside it (outputs never go into inputs).
void checkOutsideInput(const std::filesystem::path& input, const std::filesystem::path& out);

/// An output directory built under a staging name (`.OUT.partial-PID` beside OUT) and moved to
/// OUT by commit(). If the object is destroyed before commit(), the staging directory is removed,
/// so an interrupted or failed run leaves no partial output. An existing OUT is refused unless
/// `overwrite` is set (then it is replaced at commit()).
class StagedDirectory {
 public:
  StagedDirectory(std::filesystem::path out, bool overwrite);
  ~StagedDirectory();
  StagedDirectory(const StagedDirectory&) = delete;
  StagedDirectory& operator=(const StagedDirectory&) = delete;

  /// Where to write the files now.
  const std::filesystem::path& path() const { return staging_; }
  /// Final location.
  const std::filesystem::path& target() const { return out_; }
  /// Moves the staging directory to the final location.
  void commit();

 private:
  std::filesystem::path out_;
  std::filesystem::path staging_;
  bool overwrite_ = false;
  bool committed_ = false;
};

}  // namespace lidarcal::io
