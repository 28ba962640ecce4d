// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Runs a command in a child process (fork + exec) and reads the child's own resource usage
// (wait4: ru_maxrss = its peak resident memory, CPU times) with the wall time around it.
// Used by the benchmarks that measure whole `lidarcal` processes (bench_import, long_sequence).

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace lidarcal::bench {

struct Measure {
  double wall_s = 0.0;
  double user_s = 0.0;    // user-space CPU time of the child
  double system_s = 0.0;  // kernel CPU time of the child (file creation, I/O)
  long max_rss_kib = 0;   // peak resident memory of the child, KiB
  int exit_code = -1;
};

/// Runs `exe args...` with stdout discarded (errors still show on stderr).
inline Measure runChild(const std::string& exe, const std::vector<std::string>& args) {
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(exe.c_str()));
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    if (FILE* null = std::fopen("/dev/null", "w")) dup2(fileno(null), STDOUT_FILENO);
    execv(exe.c_str(), argv.data());
    std::perror("execv");
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  Measure m;
  m.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  m.max_rss_kib = usage.ru_maxrss;  // kilobytes on Linux
  m.user_s = static_cast<double>(usage.ru_utime.tv_sec) +
             1e-6 * static_cast<double>(usage.ru_utime.tv_usec);
  m.system_s = static_cast<double>(usage.ru_stime.tv_sec) +
               1e-6 * static_cast<double>(usage.ru_stime.tv_usec);
  m.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return m;
}

}  // namespace lidarcal::bench
