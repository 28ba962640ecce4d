// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Small helpers for the Cyclone DDS calls of ros2/*.cpp (private to them: includes dds/dds.h).

#include <memory>
#include <stdexcept>
#include <string>

#include <dds/dds.h>

#include "ros2/ros_participant.hpp"

namespace lidarcal::ros2 {

/// The entity (or return code), or a std::runtime_error naming `what` when Cyclone returned an
/// error code.
inline dds_entity_t checkDds(dds_entity_t e, const char* what) {
  if (e < 0)
    throw std::runtime_error(std::string("Cyclone DDS: ") + what + " failed: " + dds_strretcode(e));
  return e;
}

struct QosDeleter {
  void operator()(dds_qos_t* q) const { dds_delete_qos(q); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

/// `d` announced under another type name: discovery compares the name only (the topics carry no
/// XTypes type information), the marshalling stays that of `d`.
inline dds_topic_descriptor_t renamedType(const dds_topic_descriptor_t& d, const char* type_name) {
  return {d.m_size,  d.m_align,          d.m_flagset,    d.m_nkeys,
          type_name, d.m_keys,           d.m_nops,       d.m_ops,
          d.m_meta,  d.type_information, d.type_mapping, d.restrict_data_representation};
}

/// Cyclone's QoS for `q`, with plain CDR (XCDR version 1) as the only data representation.
inline QosPtr makeQos(const TopicQos& q) {
  QosPtr qos(dds_create_qos());
  dds_qset_reliability(qos.get(),
                       q.reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                       DDS_MSECS(100));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, q.depth);
  dds_qset_durability(qos.get(),
                      q.transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  if (q.lifespan_s > 0.0)
    dds_qset_lifespan(qos.get(), static_cast<dds_duration_t>(q.lifespan_s * 1e9));
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos.get(), 1, &xcdr1);
  return qos;
}

}  // namespace lidarcal::ros2

namespace lidarcal::ros2 {

/// Takes every sample `reader` holds (without waiting), in arrival order, and hands each valid
/// one to `each(T& sample)` while Cyclone lends it. Returns how many were handed on.
template <typename T, typename F>
std::size_t takeAll(dds_entity_t reader, F&& each) {
  constexpr int kBatch = 16;
  std::size_t handed = 0;
  for (;;) {
    void* samples[kBatch] = {nullptr};  // null: Cyclone lends the samples
    dds_sample_info_t infos[kBatch];
    const dds_return_t n = dds_take(reader, samples, infos, kBatch, kBatch);
    if (n <= 0) break;
    for (dds_return_t i = 0; i < n; ++i) {
      if (!infos[i].valid_data) continue;
      ++handed;
      each(*static_cast<T*>(samples[i]));
    }
    dds_return_loan(reader, samples, n);
    if (n < kBatch) break;
  }
  return handed;
}

}  // namespace lidarcal::ros2
