// SPDX-License-Identifier: BSD-3-Clause
#include "ros2/fastdds_peer.hpp"

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

namespace lidarcal::test {

namespace dds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;

namespace {

void applyProfile(PeerQos q, dds::ReliabilityQosPolicy& reliability, dds::HistoryQosPolicy& history,
                  dds::DurabilityQosPolicy& durability) {
  reliability.kind =
      q == PeerQos::sensor_data ? dds::BEST_EFFORT_RELIABILITY_QOS : dds::RELIABLE_RELIABILITY_QOS;
  history.kind = dds::KEEP_LAST_HISTORY_QOS;
  history.depth = q == PeerQos::sensor_data ? 5 : 10;
  durability.kind = dds::VOLATILE_DURABILITY_QOS;
}

/// Polls `done` every 5 ms for at most `seconds`.
template <typename F>
bool waitUntil(F done, double seconds) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (!done()) {
    if (Clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace

struct FastDdsPeer::Impl : public dds::DataReaderListener {
  dds::DomainParticipant* participant = nullptr;
  dds::Publisher* publisher = nullptr;
  dds::Subscriber* subscriber = nullptr;
  dds::Topic* out_topic = nullptr;
  dds::Topic* in_topic = nullptr;
  dds::DataWriter* writer = nullptr;
  dds::DataReader* reader = nullptr;
  dds::TypeSupport type{new sensor_msgs::msg::dds_::LaserScan_PubSubType()};
  mutable std::mutex mutex;
  std::vector<Ros2Scan> received;

  void on_data_available(dds::DataReader* r) override {
    Ros2Scan scan;
    dds::SampleInfo info;
    while (r->take_next_sample(&scan, &info) ==
           eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::lock_guard<std::mutex> lock(mutex);
      received.push_back(scan);
    }
  }

  dds::Topic* topic(const std::string& name) {
    if (dds::TopicDescription* d = participant->lookup_topicdescription(name))
      return static_cast<dds::Topic*>(d);
    dds::Topic* t = participant->create_topic(name, type.get_type_name(), dds::TOPIC_QOS_DEFAULT);
    if (!t) throw std::runtime_error("Fast DDS: cannot create topic " + name);
    return t;
  }
};

FastDdsPeer::FastDdsPeer(int domain_id) : impl_(std::make_unique<Impl>()) {
  dds::DomainParticipantQos pq;
  pq.name("lidarcal_test_peer");
  pq.transport().use_builtin_transports = false;  // no shared memory, no default interfaces
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.push_back("127.0.0.1");
  udp->maxInitialPeersRange = 20;  // participant indices tried at each peer
  pq.transport().user_transports.push_back(udp);
  eprosima::fastrtps::rtps::Locator_t peer;
  peer.kind = LOCATOR_KIND_UDPv4;
  eprosima::fastrtps::rtps::IPLocator::setIPv4(peer, 127, 0, 0, 1);
  pq.wire_protocol().builtin.initialPeersList.push_back(peer);
  eprosima::fastrtps::rtps::Locator_t local;  // discovery traffic on loopback unicast only
  local.kind = LOCATOR_KIND_UDPv4;
  eprosima::fastrtps::rtps::IPLocator::setIPv4(local, 127, 0, 0, 1);
  pq.wire_protocol().builtin.metatrafficUnicastLocatorList.push_back(local);
  pq.wire_protocol().default_unicast_locator_list.push_back(local);
  impl_->participant = dds::DomainParticipantFactory::get_instance()->create_participant(
      static_cast<dds::DomainId_t>(domain_id), pq);
  if (!impl_->participant) throw std::runtime_error("Fast DDS: cannot create a participant");
  impl_->type.register_type(impl_->participant);
  impl_->publisher = impl_->participant->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
  impl_->subscriber = impl_->participant->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
}

FastDdsPeer::~FastDdsPeer() {
  if (!impl_->participant) return;
  impl_->participant->delete_contained_entities();
  dds::DomainParticipantFactory::get_instance()->delete_participant(impl_->participant);
}

void FastDdsPeer::advertise(const std::string& topic, PeerQos qos) {
  unadvertise();
  dds::DataWriterQos wq = dds::DATAWRITER_QOS_DEFAULT;
  applyProfile(qos, wq.reliability(), wq.history(), wq.durability());
  impl_->writer = impl_->publisher->create_datawriter(impl_->topic(topic), wq);
  if (!impl_->writer) throw std::runtime_error("Fast DDS: cannot create a writer on " + topic);
}

void FastDdsPeer::unadvertise() {
  if (impl_->writer) impl_->publisher->delete_datawriter(impl_->writer);
  impl_->writer = nullptr;
}

void FastDdsPeer::subscribe(const std::string& topic, PeerQos qos) {
  dds::DataReaderQos rq = dds::DATAREADER_QOS_DEFAULT;
  applyProfile(qos, rq.reliability(), rq.history(), rq.durability());
  if (qos == PeerQos::reliable) rq.history().depth = 1000;  // the test reads everything it receives
  impl_->reader = impl_->subscriber->create_datareader(impl_->topic(topic), rq, impl_.get());
  if (!impl_->reader) throw std::runtime_error("Fast DDS: cannot create a reader on " + topic);
}

bool FastDdsPeer::waitMatched(double seconds) const {
  return waitUntil(
      [&] {
        dds::PublicationMatchedStatus pub;
        dds::SubscriptionMatchedStatus sub;
        const bool w = !impl_->writer ||
                       (impl_->writer->get_publication_matched_status(pub), pub.current_count > 0);
        const bool r = !impl_->reader ||
                       (impl_->reader->get_subscription_matched_status(sub), sub.current_count > 0);
        return w && r;
      },
      seconds);
}

void FastDdsPeer::publish(const Ros2Scan& scan) {
  if (!impl_->writer || !impl_->writer->write(const_cast<Ros2Scan*>(&scan)))
    throw std::runtime_error("Fast DDS: the scan could not be written");
}

bool FastDdsPeer::waitReceived(std::size_t n, double seconds) const {
  return waitUntil(
      [&] {
        std::lock_guard<std::mutex> lock(impl_->mutex);
        return impl_->received.size() >= n;
      },
      seconds);
}

std::vector<Ros2Scan> FastDdsPeer::received() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->received;
}

}  // namespace lidarcal::test
