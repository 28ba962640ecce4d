// SPDX-License-Identifier: BSD-3-Clause
#include "io/output_files.hpp"

#include <system_error>

namespace lidarcal::io {

namespace fs = std::filesystem;

void makeDirectory(const fs::path& dir) { fs::create_directories(dir); }

void copyFile(const fs::path& from, const fs::path& to) { fs::copy_file(from, to); }

ScratchDirectory::ScratchDirectory(fs::path dir) : dir_(std::move(dir)) {
  fs::remove_all(dir_);
  fs::create_directories(dir_);
}

ScratchDirectory::~ScratchDirectory() {
  std::error_code ec;  // a destructor must not throw; a leftover scratch directory is harmless
  fs::remove_all(dir_, ec);
}

void ScratchDirectory::moveOut(const std::string& name, const fs::path& target) const {
  fs::rename(dir_ / name, target);
}

}  // namespace lidarcal::io
