// SPDX-License-Identifier: BSD-3-Clause
// The `lidarcal` command: the only main, the only place that prints.

#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include <pcl/console/print.h>
#include <CLI/CLI.hpp>

#include "common/errors.hpp"
#include "pipeline/commands/cli_usage.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/words.hpp"

namespace {

/// Messages name the files a command was writing; while it writes they live in a hidden
/// staging directory (`.OUT.partial-PID-N/`) or file (`.NAME.tmp-PID-N`). Show the user the
/// final path instead.
std::string userPaths(const std::string& message) {
  std::string out;
  std::size_t i = 0;
  while (i < message.size()) {
    // A component "/.NAME.KIND-PID-N" becomes "/NAME".
    if (message.compare(i, 2, "/.") == 0) {
      const std::size_t start = i + 2;
      std::size_t end = message.find_first_of("/ :)", start);
      if (end == std::string::npos) end = message.size();
      const std::string component = message.substr(start, end - start);
      for (const char* kind : {".partial-", ".tmp-", ".probe-"}) {
        const std::size_t at = component.rfind(kind);
        if (at == std::string::npos || at == 0) continue;
        const std::string tail = component.substr(at + std::strlen(kind));  // PID-N
        const std::size_t dash = tail.find('-');
        const bool numbers = dash != std::string::npos && dash > 0 && dash + 1 < tail.size() &&
                             tail.find_first_not_of("0123456789-") == std::string::npos;
        if (!numbers) continue;
        out += "/" + component.substr(0, at);
        i = end;
        break;
      }
      if (i == end) continue;
    }
    out += message[i++];
  }
  return out;
}

/// Prints `message` on stderr, every line with the `lidarcal: ` prefix, the first after `kind`.
void printError(const std::string& kind, const std::string& message) {
  std::size_t start = 0;
  bool first = true;
  while (start <= message.size()) {
    std::size_t end = message.find('\n', start);
    if (end == std::string::npos) end = message.size();
    const std::string line = message.substr(start, end - start);
    if (first || !line.empty())
      std::fprintf(stderr, "lidarcal: %s%s\n", first ? kind.c_str() : "  ", line.c_str());
    first = false;
    start = end + 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  // PCL's readers print their own diagnostics; ours are clearer and name the file and field.
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);

  CLI::App app{
      "lidarcal: calibrate cheap 2D lidars against fixed landmarks in unknown positions, without "
      "ground truth.\n"
      "Formats: docs/FORMAT.md. Exit codes: 0 ok, 1 internal error, 2 bad input, 3 data cannot "
      "support the result."};
  app.name("lidarcal");
  lidarcal::pipeline::wrapHelp(app, lidarcal::pipeline::terminalWidth());
  app.set_version_flag("--version", LIDARCAL_VERSION);
  app.footer(
      "Method: Alhashimi et al. 2021, \"Calibrating Range Measurements of Lidars Using Fixed "
      "Landmarks in Unknown "
      "Positions\" (Sensors); Alhashimi et al. 2016, \"Statistical Modeling and Calibration of "
      "Triangulation "
      "Lidars\" (ICINCO); Sharma 2020, \"In-situ Sensor Calibration Using Noise Consistency\" (MSc "
      "thesis); "
      "`odometry`: Censi et al. 2013, \"Simultaneous calibration of odometry and sensor "
      "parameters for mobile robots\" (IEEE Transactions on Robotics). "
      "Equation numbers in "
      "the help and the reports are those of these papers.");
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "No progress output on stderr");
  app.require_subcommand(1);
  app.fallthrough();  // global flags (--quiet) may follow the subcommand
  lidarcal::pipeline::registerCommands(app);
  app.parse_complete_callback([&] { lidarcal::pipeline::setQuiet(quiet); });

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    const std::vector<std::string> args(argv + 1, argv + argc);
    for (const std::string& line : lidarcal::pipeline::parseErrorLines(app, e, args))
      std::fprintf(stderr, "lidarcal: %s\n", line.c_str());
    return 2;
  } catch (const lidarcal::DataError& e) {
    printError("cannot proceed: ", userPaths(e.what()));
    return 3;
  } catch (const lidarcal::InputError& e) {
    printError("error: ", userPaths(e.what()));
    return 2;
  } catch (const std::exception& e) {
    printError("internal error: ",
               std::string(e.what()) + "\nplease report this with the command you ran");
    return 1;
  }
  return 0;
}
