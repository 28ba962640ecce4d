// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A real single-node Slurm cluster on localhost for one test program, from Debian's packages
// (munge, slurmctld, slurmd): a MUNGE key and socket, slurm.conf, state and spool directories
// and logs in a temporary directory; the daemons in the foreground as children of the test on
// free loopback ports; clients pointed at it through SLURM_CONF. stop() cancels what is still
// queued, ends the daemons by their pid, and lists any process still naming the directory.

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "test_util.hpp"

namespace lidarcal::test {

/// `name` on PATH or in the system directories where Debian puts daemons; "" when absent.
inline std::string findProgram(const std::string& name) {
  std::string dirs = std::getenv("PATH") ? std::getenv("PATH") : "";
  dirs += ":/usr/sbin:/sbin:/usr/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t colon = std::min(dirs.find(':', start), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(start, colon - start)) / name;
    if (colon > start && ::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    start = colon + 1;
  }
  return "";
}

/// Runs `command` in a shell; returns its exit code, with stdout and stderr in `out`.
inline int shell(const std::string& command, std::string* out = nullptr) {
  static int counter = 0;
  const fs::path log = fs::temp_directory_path() / ("lidarcal-shell-" + std::to_string(::getpid()) +
                                                    "-" + std::to_string(counter++));
  const int status = std::system(("(" + command + ") >'" + log.string() + "' 2>&1").c_str());
  if (out) *out = readFile(log);
  fs::remove(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class SlurmCluster {
 public:
  /// Starts the cluster in `dir` (created). False, with the reason in `why_not`, when it cannot.
  bool start(const fs::path& dir, std::string& why_not) {
    dir_ = dir;
    for (const char* p : {"mungekey", "munged", "munge", "unmunge", "slurmctld", "slurmd", "sbatch",
                          "squeue", "sinfo", "scontrol", "scancel"})
      if (findProgram(p).empty()) {
        why_not = std::string(p) +
                  " not found (scripts/install-deps.sh installs munge, slurmctld, slurmd and "
                  "slurm-client)";
        return false;
      }
    if (::geteuid() != 0) {
      why_not = "slurmd starts jobs as their user and must run as root (run this test as root)";
      return false;
    }
    for (const char* d : {"munge", "run", "spool/ctld", "spool/d", "log"})
      fs::create_directories(dir / d);
    fs::permissions(dir / "munge", fs::perms::owner_all);  // munged refuses a key others can read
    const std::string socket = (dir / "run" / "munge.socket").string();
    if (shell(findProgram("mungekey") +
              " --create --keyfile=" + (dir / "munge" / "munge.key").string()) != 0) {
      why_not = "mungekey could not create a key";
      return false;
    }
    munged_ = std::make_unique<Child>(
        std::vector<std::string>{findProgram("munged"), "--foreground", "--force",
                                 "--socket=" + socket,
                                 "--key-file=" + (dir / "munge" / "munge.key").string(),
                                 "--log-file=" + log("munged.log"),
                                 "--pid-file=" + (dir / "run" / "munged.pid").string(),
                                 "--seed-file=" + (dir / "munge" / "seed").string()},
        log("munged.out"));
    const std::string probe = "munge -n -S '" + socket + "' | unmunge -S '" + socket + "'";
    if (!waitFor([&] { return shell(probe) == 0; }, 20.0)) {
      why_not = "munged did not answer: " + munged_->log() + readFile(log("munged.log"));
      return false;
    }
    writeConfig(socket);
    ::setenv("SLURM_CONF", conf().c_str(), 1);
    ctld_ = std::make_unique<Child>(
        std::vector<std::string>{findProgram("slurmctld"), "-D", "-f", conf()},
        log("slurmctld.out"));
    slurmd_ = std::make_unique<Child>(
        std::vector<std::string>{findProgram("slurmd"), "-D", "-N", "localhost", "-f", conf()},
        log("slurmd.out"));
    std::string state;
    if (!waitFor(
            [&] {
              return shell("sinfo -h -n localhost -o %T", &state) == 0 &&
                     state.rfind("idle", 0) == 0;
            },
            60.0)) {
      why_not = "the node did not become idle (sinfo: " + state + ")\n" + logs();
      return false;
    }
    return true;
  }

  /// Cancels every job still queued or running, stops the daemons; returns the processes still
  /// naming the cluster's directory (in their command line or environment) after that, ended.
  std::vector<std::string> stop() {
    if (slurmd_) {
      shell("scancel --quiet $(squeue -h -o %i)");
      waitFor(
          [] {
            std::string q;
            return shell("squeue -h -o %i", &q) == 0 && q.empty();
          },
          30.0);
    }
    for (auto* child : {&slurmd_, &ctld_, &munged_})
      if (*child) (*child)->stop(SIGTERM);
    std::vector<std::string> left;
    if (dir_.empty()) return left;
    for (const auto& e : fs::directory_iterator("/proc")) {
      const std::string pid = e.path().filename().string();
      if (pid.find_first_not_of("0123456789") != std::string::npos || std::stoi(pid) == ::getpid())
        continue;
      const std::string cmdline = readFile(e.path() / "cmdline"),
                        environ = readFile(e.path() / "environ");
      if (cmdline.find(dir_.string()) == std::string::npos &&
          environ.find(dir_.string()) == std::string::npos)
        continue;
      left.push_back(pid + ": " + cmdline);
      ::kill(std::stoi(pid), SIGKILL);
    }
    return left;
  }

  /// The daemons' logs, for a failure message.
  std::string logs() const {
    std::string s;
    for (const char* f :
         {"munged.out", "slurmctld.out", "slurmctld.log", "slurmd.out", "slurmd.log"})
      s += std::string("--- ") + f + "\n" + readFile(dir_ / "log" / f);
    return s;
  }

 private:
  std::string log(const std::string& name) const { return (dir_ / "log" / name).string(); }
  std::string conf() const { return (dir_ / "slurm.conf").string(); }

  /// One node of 2 CPUs, one partition; no cgroups, no accounting, every path in the directory.
  void writeConfig(const std::string& socket) const {
    const int ctld_port = freeLoopbackPort();
    int slurmd_port = freeLoopbackPort();
    while (slurmd_port == ctld_port) slurmd_port = freeLoopbackPort();
    const std::string d = dir_.string();
    std::ofstream(conf())
        << "ClusterName=lidarcaltest\nSlurmctldHost=localhost(127.0.0.1)\n"
        << "SlurmctldPort=" << ctld_port << "\nSlurmdPort=" << slurmd_port << "\n"
        << "SlurmUser=root\nSlurmdUser=root\nAuthType=auth/munge\nCredType=cred/munge\n"
        << "AuthInfo=socket=" << socket << "\n"
        << "StateSaveLocation=" << d << "/spool/ctld\nSlurmdSpoolDir=" << d << "/spool/d\n"
        << "SlurmctldPidFile=" << d << "/run/slurmctld.pid\nSlurmdPidFile=" << d
        << "/run/slurmd.pid\n"
        << "SlurmctldLogFile=" << d << "/log/slurmctld.log\nSlurmdLogFile=" << d
        << "/log/slurmd.log\n"
        << "ProctrackType=proctrack/linuxproc\nTaskPlugin=task/"
           "none\nJobAcctGatherType=jobacct_gather/none\n"
        << "AccountingStorageType=accounting_storage/none\nJobCompType=jobcomp/"
           "none\nMpiDefault=none\n"
        << "SelectType=select/cons_tres\nSelectTypeParameters=CR_Core\nSchedulerType=sched/"
           "builtin\n"
        << "ReturnToService=2\nMailProg=/bin/true\n"
        << "NodeName=localhost NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN\n"
        << "PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP\n";
  }

  fs::path dir_;
  std::unique_ptr<Child> munged_, ctld_, slurmd_;
};

}  // namespace lidarcal::test
