#include "dds_transport.hpp"

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/rtps/common/WriteParams.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>

#include "mmlio/core/error.hpp"

namespace mmlio::ros2 {
namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

namespace {

/// A type whose samples are already serialised: a ROS 2 message's CDR with its encapsulation
/// header, carried under the ROS 2 type name. What rmw does with generated code, done once here.
class SerialisedType : public dds::TopicDataType {
 public:
  explicit SerialisedType(const std::string& wire_type) {
    setName(wire_type.c_str());
    m_typeSize = 512;  // a first guess for readers' buffers; samples are unbounded (reallocated)
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, rtps::SerializedPayload_t* payload) override {
    const Cdr& cdr = *static_cast<const Cdr*>(data);
    if (cdr.size() < 4 || cdr.size() > payload->max_size) return false;
    std::memcpy(payload->data, cdr.data(), cdr.size());
    payload->length = static_cast<std::uint32_t>(cdr.size());
    payload->encapsulation = cdr[1] == 0x01 ? CDR_LE : CDR_BE;
    return true;
  }
  bool deserialize(rtps::SerializedPayload_t* payload, void* data) override {
    Cdr& cdr = *static_cast<Cdr*>(data);
    cdr.assign(payload->data, payload->data + payload->length);
    return payload->length >= 4;
  }
  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] { return static_cast<std::uint32_t>(static_cast<const Cdr*>(data)->size()); };
  }
  void* createData() override { return new Cdr(); }
  void deleteData(void* data) override { delete static_cast<Cdr*>(data); }
  bool getKey(void*, rtps::InstanceHandle_t*, bool) override { return false; }
};

template <class EndpointQos> void apply(const Qos& q, EndpointQos* out) {
  out->reliability().kind = q.reliable ? dds::RELIABLE_RELIABILITY_QOS : dds::BEST_EFFORT_RELIABILITY_QOS;
  out->durability().kind = q.transient_local ? dds::TRANSIENT_LOCAL_DURABILITY_QOS : dds::VOLATILE_DURABILITY_QOS;
  out->history().kind = dds::KEEP_LAST_HISTORY_QOS;
  out->history().depth = q.depth;
  // Samples of any size (point clouds), as rmw_fastrtps sets for unbounded types.
  out->endpoint().history_memory_policy = rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  out->data_sharing().off();
}

class FastDdsWriter : public DdsParticipant::Writer, public dds::DataWriterListener {
 public:
  bool write(const Cdr& message) override {
    return writer->write(const_cast<Cdr*>(&message));  // Fast DDS takes void*; it only reads it
  }
  bool writeReply(const Cdr& reply, const SampleIdentity& request) override {
    rtps::WriteParams params;
    rtps::SampleIdentity& related = params.related_sample_identity();
    std::memcpy(related.writer_guid().guidPrefix.value, request.writer_guid.data(), 12);
    std::memcpy(related.writer_guid().entityId.value, request.writer_guid.data() + 12, 4);
    related.sequence_number() = rtps::SequenceNumber_t(request.sequence_high, request.sequence_low);
    return writer->write(const_cast<Cdr*>(&reply), params);
  }
  int matched() const override { return matched_.load(); }
  void on_publication_matched(dds::DataWriter*, const dds::PublicationMatchedStatus& status) override {
    matched_ = status.current_count;
  }
  dds::DataWriter* writer = nullptr;

 private:
  std::atomic<int> matched_{0};
};

class FastDdsReader : public dds::DataReaderListener {
 public:
  explicit FastDdsReader(DdsParticipant::OnRequest on_sample) : on_sample_(std::move(on_sample)) {}
  void on_data_available(dds::DataReader* reader) override {
    Cdr sample;
    dds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) on_sample_(std::move(sample), replyIdentity(info));
  }

 private:
  static SampleIdentity replyIdentity(const dds::SampleInfo& info) {
    rtps::GUID_t guid = info.sample_identity.writer_guid();
    if (info.related_sample_identity.writer_guid() != rtps::GUID_t::unknown())
      guid = info.related_sample_identity.writer_guid();
    SampleIdentity id;
    std::memcpy(id.writer_guid.data(), guid.guidPrefix.value, 12);
    std::memcpy(id.writer_guid.data() + 12, guid.entityId.value, 4);
    id.sequence_high = info.sample_identity.sequence_number().high;
    id.sequence_low = info.sample_identity.sequence_number().low;
    return id;
  }

  DdsParticipant::OnRequest on_sample_;
};

}  // namespace

Qos sensorDataQos() { return {false, false, 5}; }
Qos reliableQos(int depth) { return {true, false, depth}; }
Qos latchedQos() { return {true, true, 1}; }

Transport::Kind transportKind(const std::string& name) {
  if (name == "udp") return Transport::Kind::kUdp;
  if (name == "shm") return Transport::Kind::kSharedMemory;
  if (name == "default") return Transport::Kind::kFastDdsDefault;
  throw Error("transport '" + name + "' is not one of udp, shm, default");
}

std::uint32_t grantedReceiveBuffer(std::uint32_t bytes) {
  std::ifstream in("/proc/sys/net/core/rmem_max");
  std::uint64_t rmem_max = 0;
  if (!(in >> rmem_max)) return 0;
  return static_cast<std::uint32_t>(std::min<std::uint64_t>(bytes, rmem_max));
}

namespace {

void configure(const Transport& t, dds::DomainParticipantQos* qos) {
  if (t.kind == Transport::Kind::kFastDdsDefault) return;
  qos->transport().use_builtin_transports = false;
  if (t.kind == Transport::Kind::kSharedMemory) {
    auto shm = std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>();
    shm->segment_size(t.shm_segment_bytes);
    qos->transport().user_transports.push_back(shm);
  }
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->sendBufferSize = t.socket_buffer_bytes;
  udp->receiveBufferSize = t.socket_buffer_bytes;
  qos->transport().user_transports.push_back(udp);
  qos->transport().send_socket_buffer_size = t.socket_buffer_bytes;
  qos->transport().listen_socket_buffer_size = t.socket_buffer_bytes;
}

}  // namespace

int domainIdFromEnvironment() {
  const char* env = std::getenv("ROS_DOMAIN_ID");
  if (env == nullptr || *env == '\0') return 0;
  char* end = nullptr;
  const long id = std::strtol(env, &end, 10);
  if (*end != '\0' || id < 0 || id > 232)
    throw Error(std::string("ROS_DOMAIN_ID '") + env + "' is not a domain id from 0 to 232");
  return static_cast<int>(id);
}

struct DdsParticipant::Impl {
  dds::DomainParticipant* participant = nullptr;
  dds::Publisher* publisher = nullptr;
  dds::Subscriber* subscriber = nullptr;
  std::map<std::string, dds::Topic*> topics;
  std::vector<std::unique_ptr<FastDdsWriter>> writers;
  std::vector<std::unique_ptr<FastDdsReader>> readers;

  dds::Topic* topic(const std::string& wire_topic, const std::string& wire_type) {
    if (auto it = topics.find(wire_topic); it != topics.end()) return it->second;
    if (!participant->find_type(wire_type).empty() ||
        dds::TypeSupport(new SerialisedType(wire_type)).register_type(participant) == ReturnCode_t::RETCODE_OK) {
      if (dds::Topic* t = participant->create_topic(wire_topic, wire_type, dds::TOPIC_QOS_DEFAULT))
        return topics[wire_topic] = t;
    }
    throw Error("DDS: cannot create topic " + wire_topic + " of type " + wire_type);
  }
};

DdsParticipant::DdsParticipant(int domain_id, const std::string& name, const Transport& transport)
    : impl_(std::make_unique<Impl>()) {
  dds::DomainParticipantQos qos = dds::PARTICIPANT_QOS_DEFAULT;
  qos.name(name);
  configure(transport, &qos);
  impl_->participant =
      dds::DomainParticipantFactory::get_instance()->create_participant(static_cast<dds::DomainId_t>(domain_id), qos);
  if (impl_->participant == nullptr) throw Error("DDS: cannot join domain " + std::to_string(domain_id));
  impl_->publisher = impl_->participant->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
  impl_->subscriber = impl_->participant->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
  if (impl_->publisher == nullptr || impl_->subscriber == nullptr)
    throw Error("DDS: cannot create a publisher and a subscriber in domain " + std::to_string(domain_id));
}

DdsParticipant::~DdsParticipant() {
  if (impl_->participant == nullptr) return;
  impl_->participant->delete_contained_entities();
  dds::DomainParticipantFactory::get_instance()->delete_participant(impl_->participant);
}

DdsParticipant::Writer& DdsParticipant::writer(const std::string& wire_topic, const std::string& wire_type,
                                               const Qos& qos) {
  dds::DataWriterQos wq = dds::DATAWRITER_QOS_DEFAULT;
  apply(qos, &wq);
  // Synchronous, as rmw_fastrtps publishes since Galactic: a sample leaves in write(), so a burst
  // of small ones (IMU) never waits behind a large one (a point cloud) in a keep-last history.
  wq.publish_mode().kind = dds::SYNCHRONOUS_PUBLISH_MODE;
  auto w = std::make_unique<FastDdsWriter>();
  w->writer = impl_->publisher->create_datawriter(impl_->topic(wire_topic, wire_type), wq, w.get());
  if (w->writer == nullptr) throw Error("DDS: cannot create a writer of " + wire_topic);
  impl_->writers.push_back(std::move(w));
  return *impl_->writers.back();
}

void DdsParticipant::reader(const std::string& wire_topic, const std::string& wire_type, const Qos& qos,
                            OnMessage on_message) {
  requestReader(wire_topic, wire_type, qos, [on_message = std::move(on_message)](Cdr&& message, const SampleIdentity&) {
    on_message(std::move(message));
  });
}

void DdsParticipant::requestReader(const std::string& wire_topic, const std::string& wire_type, const Qos& qos,
                                   OnRequest on_request) {
  dds::DataReaderQos rq = dds::DATAREADER_QOS_DEFAULT;
  apply(qos, &rq);
  auto r = std::make_unique<FastDdsReader>(std::move(on_request));
  if (impl_->subscriber->create_datareader(impl_->topic(wire_topic, wire_type), rq, r.get()) == nullptr)
    throw Error("DDS: cannot create a reader of " + wire_topic);
  impl_->readers.push_back(std::move(r));
}

}  // namespace mmlio::ros2
