// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The DDS tests' environment: a domain of the run's own and a Cyclone DDS configuration on
// loopback only, so that test runs on one machine neither hear each other nor leave it.

#include <unistd.h>

#include <chrono>
#include <string>

namespace lidarcal::test {

/// A Cyclone DDS configuration (for CYCLONEDDS_URI) restricted to loopback: no multicast, the
/// participants of this machine found through unicast peers at 127.0.0.1.
inline std::string cycloneLoopbackConfig() {
  return "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
         "address=\"127.0.0.1\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</"
         "ParticipantIndex>"
         "<MaxAutoParticipantIndex>20</MaxAutoParticipantIndex><Peers><Peer "
         "address=\"127.0.0.1\"/></Peers></Discovery>"
         "</Domain></CycloneDDS>";
}

/// A domain id for one test run (first..first+count-1, default 1..200, from the process id and
/// the clock): separate runs on one machine do not hear each other, and a suite given a range of
/// its own never shares a domain with the others.
inline int uniqueDomainId(int first = 1, int count = 200) {
  const auto t =
      static_cast<unsigned long>(std::chrono::steady_clock::now().time_since_epoch().count());
  return first + static_cast<int>((static_cast<unsigned long>(getpid()) * 7919ul + t) %
                                  static_cast<unsigned long>(count));
}

}  // namespace lidarcal::test
