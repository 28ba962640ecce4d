#include "pipeline/gnuplot.hpp"

#include <cstdlib>

namespace lidarcal::pipeline {

bool runGnuplot(const std::filesystem::path& dir, const std::string& script, std::string* why) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    if (why) *why = "gnuplot is not installed (apt-get install gnuplot-nox); plots skipped";
    return false;
  }
  const std::string cmd = "cd '" + dir.string() + "' && gnuplot '" + script + "' >/dev/null 2>gnuplot.log";
  if (std::system(cmd.c_str()) != 0) {
    if (why) *why = "gnuplot failed, see " + (dir / "gnuplot.log").string();
    return false;
  }
  std::error_code ec;
  std::filesystem::remove(dir / "gnuplot.log", ec);
  return true;
}

}  // namespace lidarcal::pipeline
