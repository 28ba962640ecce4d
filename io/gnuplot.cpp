// SPDX-License-Identifier: BSD-3-Clause
#include "io/gnuplot.hpp"

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string_view>

namespace lidarcal::io {

bool gnuplotInstalled() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

std::string gnuplotBroken(const std::filesystem::path& log) {
  if (std::system("gnuplot -e 'set terminal pngcairo; set terminal svg' </dev/null >/dev/null "
                  "2>&1") == 0)
    return {};
  std::string first;
  std::ifstream in(log);
  std::getline(in, first);
  return "gnuplot does not start or lacks the pngcairo and svg terminals" +
         (first.empty() ? std::string() : " (" + first + ")") + "; " + kGnuplotPackage;
}

namespace {

/// The last non-empty line of gnuplot's log: its error, after any warnings.
std::string lastMessage(const std::filesystem::path& log) {
  std::ifstream in(log);
  std::string line, last = "no message";
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  return last;
}

}  // namespace

bool runGnuplot(const std::filesystem::path& dir, const std::string& script, std::string* why) {
  if (!gnuplotInstalled()) {
    if (why)
      *why = std::string("gnuplot is not installed (") + kGnuplotPackage + "); plots skipped";
    return false;
  }
  const std::string cmd =
      "cd '" + dir.string() + "' && gnuplot '" + script + "' >/dev/null 2>gnuplot.log";
  if (std::system(cmd.c_str()) != 0) {
    const std::string broken = gnuplotBroken(dir / "gnuplot.log");
    if (why)
      *why = broken.empty()
                 ? "gnuplot failed on " + script + ": " + lastMessage(dir / "gnuplot.log")
                 : broken + "; plots skipped";
    return false;
  }
  std::error_code ec;
  std::filesystem::remove(dir / "gnuplot.log", ec);
  return true;
}

std::string gnuplotLog(const std::filesystem::path& dir, std::size_t max_chars) {
  std::ifstream in(dir / "gnuplot.log");
  std::string log((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (log.size() > max_chars) log = log.substr(0, max_chars) + "...";
  return log;
}

std::string gnuplotString(const std::string& text, bool enhanced) {
  // A backslash escapes inside a double-quoted gnuplot string; enhanced text then reads the
  // resulting `\_` as a literal `_`.
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\')
      out += '\\';
    else if (enhanced && std::string_view("_^{}@&~").find(c) != std::string_view::npos)
      out += "\\\\";
    out += c;
  }
  return out + "\"";
}

}  // namespace lidarcal::io
