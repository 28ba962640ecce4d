// SPDX-License-Identifier: BSD-3-Clause
#include "ros2/ros_participant.hpp"

#include <algorithm>
#include <cstring>

#include "ros2/cyclone_util.hpp"
#include "ros2/graph_publisher.hpp"

namespace lidarcal::ros2 {

TopicQos topicQos(QosProfile profile) {
  TopicQos q;
  q.reliable = profile != QosProfile::sensor_data;
  q.depth = profile == QosProfile::sensor_data ? 5 : 10;
  return q;
}

TopicQos latchedQos() {
  TopicQos q;
  q.reliable = true;
  q.transient_local = true;
  q.depth = 1;
  return q;
}

Guid RosParticipant::guidOf(int entity) {
  dds_guid_t g;
  checkDds(dds_get_guid(entity, &g), "reading an entity's GUID");
  Guid out;
  static_assert(sizeof g.v == sizeof(Guid), "a DDS GUID is 16 bytes");
  std::memcpy(out.data(), g.v, out.size());
  return out;
}

RosParticipant::RosParticipant(const ParticipantSettings& s) {
  QosPtr pq(dds_create_qos());
  dds_qset_entity_name(pq.get(), s.node_name.c_str());
  // As rmw_cyclonedds_cpp (rmw_node.cpp): the participant's security enclave in its user data.
  const std::string user_data = "enclave=/;";
  dds_qset_userdata(pq.get(), user_data.data(), user_data.size());
  participant_ =
      dds_create_participant(static_cast<dds_domainid_t>(s.domain_id), pq.get(), nullptr);
  checkDds(
      participant_,
      "creating the participant (domain from ROS_DOMAIN_ID, configuration from CYCLONEDDS_URI)");
  try {
    graph_ = std::make_unique<GraphPublisher>(participant_, s.ros_distro);
    entities_.node_namespace = s.node_namespace;
    entities_.node_name = s.node_name;
    announce();
  } catch (...) {
    dds_delete(participant_);
    throw;
  }
}

RosParticipant::~RosParticipant() { dds_delete(participant_); }  // and everything it holds

Guid RosParticipant::guid() const { return guidOf(participant_); }

int RosParticipant::topic(const std::string& dds_topic, const dds_topic_descriptor& type) {
  const auto it = topics_.find(dds_topic);
  if (it != topics_.end()) return it->second;
  const dds_entity_t t =
      checkDds(dds_create_topic(participant_, &type, dds_topic.c_str(), nullptr, nullptr),
               ("creating the topic " + dds_topic).c_str());
  topics_[dds_topic] = t;
  return t;
}

int RosParticipant::createEndpoint(bool reader, const std::string& dds_topic,
                                   const dds_topic_descriptor& type, const TopicQos& qos) {
  const dds_entity_t t = topic(dds_topic, type);
  const QosPtr q = makeQos(qos);
  const dds_entity_t e = reader ? dds_create_reader(participant_, t, q.get(), nullptr)
                                : dds_create_writer(participant_, t, q.get(), nullptr);
  checkDds(e, ((reader ? "creating a reader on " : "creating a writer on ") + dds_topic).c_str());
  (reader ? readers_ : writers_).emplace_back(e, guidOf(e));
  announce();
  return e;
}

int RosParticipant::createWriter(const std::string& dds_topic, const dds_topic_descriptor& type,
                                 const TopicQos& qos) {
  return createEndpoint(false, dds_topic, type, qos);
}

int RosParticipant::createReader(const std::string& dds_topic, const dds_topic_descriptor& type,
                                 const TopicQos& qos) {
  return createEndpoint(true, dds_topic, type, qos);
}

void RosParticipant::deleteEntity(int entity) {
  const auto other = [entity](const std::pair<int, Guid>& e) { return e.first != entity; };
  const std::size_t before = readers_.size() + writers_.size();
  readers_.erase(std::stable_partition(readers_.begin(), readers_.end(), other), readers_.end());
  writers_.erase(std::stable_partition(writers_.begin(), writers_.end(), other), writers_.end());
  if (readers_.size() + writers_.size() == before) return;  // not one of the node's
  dds_delete(entity);
  announce();
}

void RosParticipant::announce() {
  entities_.readers.clear();
  entities_.writers.clear();
  for (const auto& [handle, guid] : readers_) entities_.readers.push_back(guid);
  for (const auto& [handle, guid] : writers_) entities_.writers.push_back(guid);
  graph_->publish(guid(), entities_);
  ++announcements_;
}

}  // namespace lidarcal::ros2
