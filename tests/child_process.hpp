// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Child processes for the tests that start servers (rosmaster, the Slurm daemons): started by
// fork + exec with their output in a log file, waited for with bounded polls, stopped by their
// pid (a signal, then SIGKILL), and a free loopback port for them to listen on.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
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
  /// `signal` (default SIGINT, a ROS node's Ctrl-C; SIGTERM for a daemon), then SIGKILL after 10 s;
  /// returns the exit status.
  int stop(int signal = SIGINT) {
    if (pid_ > 0) {
      kill(pid_, signal);
      if (!waitExit(10.0) && pid_ > 0) {
        kill(pid_, SIGKILL);
        waitExit(5.0);
      }
    }
    return status_.value_or(-1);
  }
  std::string log() const { return readFile(log_); }
  /// The process id (-1 once it has ended and been waited for).
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
  fs::path log_;
};

/// A TCP port on 127.0.0.1 that nothing listens on now (-1 when none could be had).
inline int freeLoopbackPort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t len = sizeof a;
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    close(fd);
    return -1;
  }
  close(fd);
  return ntohs(a.sin_port);
}

}  // namespace lidarcal::test
