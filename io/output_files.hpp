// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The file-system steps of writing outputs that are not one file's bytes: directories inside a
// staged output, an input file kept beside the outputs, and a scratch directory for files another
// program (gnuplot) writes before one of them is moved into place.

#include <filesystem>
#include <string>

namespace lidarcal::io {

/// Makes `dir` and any missing parents; nothing when it exists.
void makeDirectory(const std::filesystem::path& dir);

/// Copies the file `from` to `to` (an input's metadata carried into an output directory).
void copyFile(const std::filesystem::path& from, const std::filesystem::path& to);

/// A directory made empty on construction and removed with its contents on destruction, so a
/// failed or interrupted run leaves nothing behind. moveOut() moves one finished file out of it.
class ScratchDirectory {
 public:
  explicit ScratchDirectory(std::filesystem::path dir);
  ~ScratchDirectory();
  ScratchDirectory(const ScratchDirectory&) = delete;
  ScratchDirectory& operator=(const ScratchDirectory&) = delete;

  const std::filesystem::path& path() const { return dir_; }
  /// Renames `name` (inside the scratch directory) onto `target`.
  void moveOut(const std::string& name, const std::filesystem::path& target) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace lidarcal::io
