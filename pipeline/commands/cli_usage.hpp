// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How `lidarcal` answers at the command line: help wrapped to the terminal's width, and parse
// errors that list what was not understood in the order it was given, with the nearest command or
// option as a suggestion (a slip of one or two letters, or the start of a longer name).

#include <cstddef>
#include <string>
#include <vector>

namespace CLI {
class App;
class ParseError;
}  // namespace CLI

namespace lidarcal::pipeline {

/// Columns of the terminal that standard output writes to; 80 when it is not a terminal.
std::size_t terminalWidth();

/// `text` with every line longer than `width` broken at spaces. A continued line starts at the
/// line's description column when it has one (`column`: where CLI11 puts the description beside
/// an option or command name), else at the line's own indentation. A word longer than the room
/// left stays whole.
std::string wrapText(const std::string& text, std::size_t width, std::size_t column);

/// Makes `app` print its help wrapped to `width` columns; subcommands added afterwards inherit it.
void wrapHelp(CLI::App& app, std::size_t width);

/// Optimal string alignment distance: the insertions, deletions, substitutions and swaps of two
/// neighbouring characters that turn `a` into `b`.
std::size_t editDistance(const std::string& a, const std::string& b);

/// The candidate `word` is most likely a slip for: the only candidate that begins with `word` (3
/// characters or more), else the nearest one when it is at most a third of the word's length away
/// (at least 1); empty when there is none. Leading dashes count as part of the names.
std::string nearestName(const std::string& word, const std::vector<std::string>& candidates);

/// What to print for a parse error other than a request for help or the version: lines without
/// the `lidarcal: ` prefix, the first naming the problem, the last where to read more. `args` are
/// the command line's arguments after the program name, in the order given.
std::vector<std::string> parseErrorLines(const CLI::App& app, const CLI::ParseError& error,
                                         const std::vector<std::string>& args);

}  // namespace lidarcal::pipeline
