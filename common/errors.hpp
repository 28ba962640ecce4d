// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Errors a user can act on: which file, which item, what is wrong, what to do.

#include <stdexcept>
#include <string>

namespace lidarcal {

/// Bad input (a file, a field, a command-line value). The command prints it and exits nonzero.
class InputError : public std::runtime_error {
 public:
  /// file: the path concerned (may be empty); item: field, line or option; problem: what is wrong;
  /// remedy: what the user can do about it.
  InputError(std::string file, std::string item, std::string problem, std::string remedy = {})
      : std::runtime_error(compose(file, item, problem, remedy)),
        file_(std::move(file)),
        item_(std::move(item)),
        problem_(std::move(problem)),
        remedy_(std::move(remedy)) {}

  const std::string& file() const { return file_; }
  const std::string& item() const { return item_; }
  const std::string& problem() const { return problem_; }
  const std::string& remedy() const { return remedy_; }

 private:
  static std::string compose(const std::string& file, const std::string& item,
                             const std::string& problem, const std::string& remedy) {
    std::string text;
    if (!file.empty()) text += file + ": ";
    if (!item.empty()) text += item + ": ";
    text += problem;
    if (!remedy.empty()) text += " (" + remedy + ")";
    return text;
  }
  std::string file_, item_, problem_, remedy_;
};

/// A stage could not produce a result for the data given (degenerate geometry, too few
/// observations). Carries the same fields as InputError; the command exits nonzero.
class DataError : public InputError {
 public:
  using InputError::InputError;
};

}  // namespace lidarcal
