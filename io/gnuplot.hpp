// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Plots through gnuplot (Debian's gnuplot-nox): the report writes data files and a script,
// this runs it. A missing gnuplot is not an error: the report says the plots were skipped. A
// command whose output is a picture (`plot`, `montecarlo`'s figures when gnuplot is installed)
// refuses with exit code 2 when gnuplot cannot draw, naming the package to install.

#include <cstddef>
#include <filesystem>
#include <string>

namespace lidarcal::io {

/// The Debian package that draws every plot lidarcal makes, and how to install it.
inline constexpr const char* kGnuplotPackage = "apt-get install gnuplot-nox";

/// Whether a `gnuplot` program is on the PATH.
bool gnuplotInstalled();

/// Why an installed gnuplot cannot draw here (it does not start, or lacks the pngcairo and svg
/// terminals), with the first line of `log` (gnuplot's messages) and the package to install;
/// empty when gnuplot draws, so a failure lies in the script.
std::string gnuplotBroken(const std::filesystem::path& log);

/// Runs `gnuplot script` in `dir`. Returns false when gnuplot is missing or fails, with a reason
/// that quotes gnuplot's last message rather than a path: `dir` may be a staging directory.
bool runGnuplot(const std::filesystem::path& dir, const std::string& script,
                std::string* why = nullptr);

/// gnuplot's messages from its last failed run in `dir` (the log runGnuplot keeps), at most
/// `max_chars` of them followed by "..." when longer; empty when there is none.
std::string gnuplotLog(const std::filesystem::path& dir, std::size_t max_chars);

/// `text` as a double-quoted gnuplot string that shows as written. `enhanced`: the terminal uses
/// enhanced text mode, so its markup characters (_ ^ { } @ & ~) are escaped too (a file name
/// like scan_000000.pcd would otherwise turn into a subscript).
std::string gnuplotString(const std::string& text, bool enhanced = false);

}  // namespace lidarcal::io
