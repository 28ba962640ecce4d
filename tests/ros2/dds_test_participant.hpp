// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A Cyclone DDS participant of the test's own, beside the code under test: writers of samples
// the test fills, readers that keep the bytes as they arrive (the CDR a writer put on the wire,
// encapsulation header included), and the endpoints the DDS builtin topics report. Every wait is
// bounded.

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <gtest/gtest.h>

#include "child_process.hpp"
#include "ros2/cyclone_util.hpp"
#include "ros2/dds_test_env.hpp"
#include "ros2/ros_participant.hpp"

namespace lidarcal::test {

/// An endpoint as DCPSPublication / DCPSSubscription report it.
struct DiscoveredEndpoint {
  ros2::Guid guid;          ///< the endpoint's GUID
  ros2::Guid participant;   ///< its participant's GUID
  std::string topic, type;  ///< DDS topic and type names
};

/// This run's domain, chosen once; ROS_DOMAIN_ID and CYCLONEDDS_URI (loopback only) are set for
/// the participants the test makes and the nodes it starts.
inline int testDomain() {
  static const int domain = [] {
    const int d = uniqueDomainId();
    setenv("ROS_DOMAIN_ID", std::to_string(d).c_str(), 1);
    setenv("CYCLONEDDS_URI", cycloneLoopbackConfig().c_str(), 1);
    return d;
  }();
  return domain;
}

/// A test parameterised by ROS 2 release: the release's name.
inline std::string releaseName(const ::testing::TestParamInfo<ros2::RosDistro>& p) {
  return ros2::toString(p.param);
}

/// Bytes as two hex digits each, for readable comparisons.
inline std::string hex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (unsigned char c : bytes) {
    out += digits[c >> 4];
    out += digits[c & 15];
    out += ' ';
  }
  return out;
}

class TestParticipant {
 public:
  explicit TestParticipant(int domain) {
    participant_ = dds_create_participant(static_cast<dds_domainid_t>(domain), nullptr, nullptr);
    if (participant_ < 0) throw std::runtime_error("test: cannot create a Cyclone participant");
  }
  ~TestParticipant() { dds_delete(participant_); }
  TestParticipant(const TestParticipant&) = delete;
  TestParticipant& operator=(const TestParticipant&) = delete;

  dds_entity_t handle() const { return participant_; }

  /// A writer of `type` on `topic` with plain CDR (XCDR1), reliable unless `qos` says otherwise.
  dds_entity_t writer(const std::string& topic, const dds_topic_descriptor_t& type,
                      const ros2::TopicQos& qos = {}) {
    return endpoint(false, topic, type, qos);
  }
  /// A reader whose samples are kept as received bytes (rawSamples).
  dds_entity_t reader(const std::string& topic, const dds_topic_descriptor_t& type,
                      const ros2::TopicQos& qos = {}) {
    return endpoint(true, topic, type, qos);
  }
  /// Waits at most `seconds` until the writer or reader `e` has matched one of the other kind.
  static bool waitMatched(dds_entity_t e, double seconds) {
    return waitFor(
        [&] {
          dds_publication_matched_status_t w;
          dds_subscription_matched_status_t r;
          return (dds_get_publication_matched_status(e, &w) == DDS_RETCODE_OK &&
                  w.current_count > 0) ||
                 (dds_get_subscription_matched_status(e, &r) == DDS_RETCODE_OK &&
                  r.current_count > 0);
        },
        seconds);
  }

  /// Every sample `r` received so far, as the CDR bytes received (kept across calls).
  const std::vector<std::string>& rawSamples(dds_entity_t r) {
    std::vector<std::string>& kept = raw_[r];
    for (;;) {
      ddsi_serdata* d = nullptr;
      dds_sample_info_t info;
      if (dds_takecdr(r, &d, 1, &info, 0) <= 0) break;
      if (info.valid_data) {
        std::string bytes(ddsi_serdata_size(d), '\0');
        ddsi_serdata_to_ser(d, 0, bytes.size(), bytes.data());
        kept.push_back(std::move(bytes));
      }
      ddsi_serdata_unref(d);
    }
    return kept;
  }
  /// Waits at most `seconds` until `r` has received `n` samples.
  bool waitSamples(dds_entity_t r, std::size_t n, double seconds) {
    return waitFor([&] { return rawSamples(r).size() >= n; }, seconds);
  }

  /// The writers (publications = true) or readers the builtin topics reported so far.
  std::vector<DiscoveredEndpoint> endpoints(bool publications) {
    dds_entity_t& r = publications ? publications_ : subscriptions_;
    if (r == 0)
      r = dds_create_reader(
          participant_,
          publications ? DDS_BUILTIN_TOPIC_DCPSPUBLICATION : DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION,
          nullptr, nullptr);
    void* samples[64] = {nullptr};
    dds_sample_info_t infos[64];
    const dds_return_t n = dds_read(r, samples, infos, 64, 64);  // read: kept for the next call
    std::vector<DiscoveredEndpoint> out;
    for (dds_return_t i = 0; i < n; ++i) {
      if (!infos[i].valid_data || infos[i].instance_state != DDS_IST_ALIVE) continue;
      const auto* e = static_cast<const dds_builtintopic_endpoint_t*>(samples[i]);
      DiscoveredEndpoint d;
      std::memcpy(d.guid.data(), e->key.v, 16);
      std::memcpy(d.participant.data(), e->participant_key.v, 16);
      d.topic = e->topic_name;
      d.type = e->type_name;
      out.push_back(d);
    }
    if (n > 0) dds_return_loan(r, samples, n);
    return out;
  }

 private:
  dds_entity_t endpoint(bool reader, const std::string& topic, const dds_topic_descriptor_t& type,
                        const ros2::TopicQos& qos) {
    const dds_entity_t t = this->topic(topic, type);
    const ros2::QosPtr q = ros2::makeQos(qos);
    const dds_entity_t e = reader ? dds_create_reader(participant_, t, q.get(), nullptr)
                                  : dds_create_writer(participant_, t, q.get(), nullptr);
    if (e < 0) throw std::runtime_error("test: cannot create an endpoint on " + topic);
    return e;
  }
  dds_entity_t topic(const std::string& name, const dds_topic_descriptor_t& type) {
    const auto it = topics_.find(name);
    if (it != topics_.end()) return it->second;
    const dds_entity_t t = dds_create_topic(participant_, &type, name.c_str(), nullptr, nullptr);
    if (t < 0) throw std::runtime_error("test: cannot create the topic " + name);
    return topics_[name] = t;
  }

  dds_entity_t participant_ = 0, publications_ = 0, subscriptions_ = 0;
  std::map<std::string, dds_entity_t> topics_;
  std::map<dds_entity_t, std::vector<std::string>> raw_;
};

}  // namespace lidarcal::test
