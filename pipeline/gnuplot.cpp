// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/gnuplot.hpp"

#include <cstdlib>
#include <string_view>

namespace lidarcal::pipeline {

bool runGnuplot(const std::filesystem::path& dir, const std::string& script, std::string* why) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    if (why) *why = "gnuplot is not installed (apt-get install gnuplot-nox); plots skipped";
    return false;
  }
  const std::string cmd =
      "cd '" + dir.string() + "' && gnuplot '" + script + "' >/dev/null 2>gnuplot.log";
  if (std::system(cmd.c_str()) != 0) {
    if (why) *why = "gnuplot failed, see " + (dir / "gnuplot.log").string();
    return false;
  }
  std::error_code ec;
  std::filesystem::remove(dir / "gnuplot.log", ec);
  return true;
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

}  // namespace lidarcal::pipeline
