// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Plots through gnuplot (Debian's gnuplot-nox): the report writes data files and a script,
// this runs it. A missing gnuplot is not an error: the report says the plots were skipped.

#include <filesystem>
#include <string>

namespace lidarcal::pipeline {

/// Runs `gnuplot script` in `dir`. Returns false (with a reason) when gnuplot is missing or fails.
bool runGnuplot(const std::filesystem::path& dir, const std::string& script,
                std::string* why = nullptr);

/// `text` as a double-quoted gnuplot string that shows as written. `enhanced`: the terminal uses
/// enhanced text mode, so its markup characters (_ ^ { } @ & ~) are escaped too (a file name
/// like scan_000000.pcd would otherwise turn into a subscript).
std::string gnuplotString(const std::string& text, bool enhanced = false);

}  // namespace lidarcal::pipeline
