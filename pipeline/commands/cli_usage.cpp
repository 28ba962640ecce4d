// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/commands/cli_usage.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <sstream>

#include <CLI/CLI.hpp>

namespace lidarcal::pipeline {
namespace {

/// CLI11's help, each page wrapped to a width.
class WrappingFormatter : public CLI::Formatter {
 public:
  explicit WrappingFormatter(std::size_t width) : width_(width) {}
  std::string make_help(const CLI::App* app, std::string name,
                        CLI::AppFormatMode mode) const override {
    return wrapText(CLI::Formatter::make_help(app, std::move(name), mode), width_,
                    get_column_width());
  }

 private:
  std::size_t width_;
};

/// One line broken at spaces into lines of at most `width` characters (see wrapText).
std::string wrapLine(const std::string& line, std::size_t width, std::size_t column) {
  const std::size_t own = line.find_first_not_of(' ');
  if (line.size() <= width || own == std::string::npos) return line;
  // CLI11 starts a name at column 2 and its description at `column`.
  const bool described =
      own == 2 && line.size() > column && line[column - 1] == ' ' && line[column] != ' ';
  std::size_t start = described ? column : own, indent = start;
  if (indent + 20 > width) indent = own + 20 > width ? 0 : own;
  std::string out = line.substr(0, start), word;
  std::size_t length = out.size();
  bool line_empty = true;  // nothing but indentation on the current line yet
  std::istringstream words(line.substr(start));
  while (words >> word) {
    if (!line_empty && length + 1 + word.size() > width) {
      out += "\n" + std::string(indent, ' ');
      length = indent;
      line_empty = true;
    }
    if (!line_empty) {
      out += ' ';
      ++length;
    }
    out += word;
    length += word.size();
    line_empty = false;
  }
  return out;
}

bool isNumber(const std::string& s) {
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return !s.empty() && end && *end == '\0';
}

bool isOption(const std::string& arg) { return arg.size() > 1 && arg[0] == '-' && !isNumber(arg); }

/// The names a user can type for the options of `app` and of the program (--quiet, --version).
std::vector<std::string> optionNames(const CLI::App& app, const CLI::App& program) {
  std::vector<std::string> names;
  const auto add = [&](const CLI::App& a) {
    for (const CLI::Option* o : a.get_options()) {
      for (const std::string& n : o->get_lnames()) names.push_back("--" + n);
      for (const std::string& n : o->get_snames()) names.push_back("-" + n);
    }
  };
  add(app);
  if (&app != &program) add(program);
  return names;
}

/// `extras` (CLI11 collects them in its own order) in the order the user gave them in `args`.
std::vector<std::string> inGivenOrder(const std::vector<std::string>& extras,
                                      const std::vector<std::string>& args) {
  std::vector<std::string> ordered;
  std::vector<bool> placed(extras.size(), false);
  for (const std::string& arg : args)
    for (std::size_t i = 0; i < extras.size(); ++i)
      if (!placed[i] && extras[i] == arg) {
        ordered.push_back(arg);
        placed[i] = true;
        break;
      }
  for (std::size_t i = 0; i < extras.size(); ++i)
    if (!placed[i]) ordered.push_back(extras[i]);
  return ordered;
}

std::string joined(const std::vector<std::string>& words) {
  std::string out;
  for (const std::string& w : words) out += (out.empty() ? "" : " ") + w;
  return out;
}

/// The lines for arguments nobody expected: the list as given, then a suggestion per option.
std::vector<std::string> extrasLines(const std::string& where,
                                     const std::vector<std::string>& extras,
                                     const std::vector<std::string>& options) {
  std::vector<std::string> lines{"error: " + where + "not expected: " + joined(extras)};
  for (const std::string& extra : extras) {
    if (!isOption(extra)) continue;
    const std::string name = extra.substr(0, extra.find('='));
    const std::string near = nearestName(name, options);
    lines.push_back(name + ": unknown option" +
                    (near.empty() ? std::string() : "; did you mean " + near + "?"));
  }
  return lines;
}

std::vector<std::string> commandNames(const CLI::App& program) {
  std::vector<std::string> names;
  for (const CLI::App* sub : program.get_subcommands([](const CLI::App*) { return true; }))
    names.push_back(sub->get_name());
  return names;
}

}  // namespace

std::size_t terminalWidth() {
  winsize size{};
  if (::isatty(STDOUT_FILENO) && ::ioctl(STDOUT_FILENO, TIOCGWINSZ, &size) == 0 &&
      size.ws_col >= 40)
    return size.ws_col;
  return 80;
}

std::string wrapText(const std::string& text, std::size_t width, std::size_t column) {
  std::string out;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    const bool newline = end != std::string::npos;
    if (!newline) end = text.size();
    out += wrapLine(text.substr(start, end - start), width, column);
    if (newline) out += '\n';
    start = end + 1;
  }
  return out;
}

void wrapHelp(CLI::App& app, std::size_t width) {
  app.formatter(std::make_shared<WrappingFormatter>(width));
}

std::size_t editDistance(const std::string& a, const std::string& b) {
  // d[i][j]: distance between the first i characters of a and the first j of b.
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substitution = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + substitution});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

std::string nearestName(const std::string& word, const std::vector<std::string>& candidates) {
  std::vector<std::string> longer;
  for (const std::string& c : candidates)
    if (c.size() > word.size() && c.compare(0, word.size(), word) == 0) longer.push_back(c);
  if (word.size() >= 3 && longer.size() == 1) return longer.front();
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(1, word.size() / 3) + 1;
  for (const std::string& c : candidates)
    if (const std::size_t d = editDistance(word, c); d < best_distance) {
      best = c;
      best_distance = d;
    }
  return best;
}

std::vector<std::string> parseErrorLines(const CLI::App& program, const CLI::ParseError& error,
                                         const std::vector<std::string>& args) {
  const std::vector<CLI::App*> parsed = program.get_subcommands();
  const CLI::App* command = parsed.empty() ? nullptr : parsed.front();
  const std::vector<std::string> extras = inGivenOrder(program.remaining(true), args);
  if (!command) {
    const auto word =
        std::find_if(args.begin(), args.end(), [](const std::string& a) { return !isOption(a); });
    if (word != args.end()) {
      const std::string near = nearestName(*word, commandNames(program));
      return {"error: '" + *word + "' is not a lidarcal command" +
                  (near.empty() ? std::string() : "; did you mean `" + near + "`?"),
              "`lidarcal --help` lists the commands"};
    }
  }
  const std::string where = command ? command->get_name() + ": " : std::string();
  std::vector<std::string> lines;
  if (!extras.empty())
    lines = extrasLines(where, extras, optionNames(command ? *command : program, program));
  if (!command)
    lines.push_back("error: a command is required: lidarcal COMMAND [OPTIONS]");
  else if (dynamic_cast<const CLI::ExtrasError*>(&error) == nullptr)
    lines.push_back("error: " + where + error.what());
  lines.push_back(command ? "`lidarcal " + command->get_name() + " --help` lists its options"
                          : "`lidarcal --help` lists the commands");
  return lines;
}

}  // namespace lidarcal::pipeline
