#pragma once
// A node under test as a child process (fork + exec, stdout and stderr into a log file), ended
// by its pid only; and a bounded poll. Shared by the ROS 1 and ROS 2 node tests.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "test_util.hpp"

namespace lidarcal::test {

using Clock = std::chrono::steady_clock;

/// Polls `done` every 10 ms for at most `seconds`.
inline bool waitFor(const std::function<bool()>& done, double seconds) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

/// A child process with stdout and stderr in `log`.
class Child {
 public:
  Child(const std::vector<std::string>& argv, const fs::path& log) : log_(log) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_ = fork();
    if (pid_ == 0) {
      if (FILE* f = std::fopen(log.c_str(), "w")) {
        dup2(fileno(f), STDOUT_FILENO);
        dup2(fileno(f), STDERR_FILENO);
      }
      execvp(args[0], args.data());
      std::perror("execvp");
      _exit(127);
    }
  }
  ~Child() { stop(); }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  /// Exit status once it has ended by itself within `seconds`, else nothing.
  std::optional<int> waitExit(double seconds) {
    if (pid_ <= 0) return status_;
    int status = 0;
    const bool ended = waitFor([&] { return waitpid(pid_, &status, WNOHANG) == pid_; }, seconds);
    if (!ended) return std::nullopt;
    pid_ = -1;
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return status_;
  }
  /// SIGINT (a ROS node's Ctrl-C), then SIGKILL after 10 s; returns the exit status.
  int stop() {
    if (pid_ > 0) {
      kill(pid_, SIGINT);
      if (!waitExit(10.0) && pid_ > 0) {
        kill(pid_, SIGKILL);
        waitExit(5.0);
      }
    }
    return status_.value_or(-1);
  }
  std::string log() const { return readFile(log_); }

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
  fs::path log_;
};

}  // namespace lidarcal::test
