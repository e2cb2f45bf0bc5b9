// Test tool: calls the node's save_map service as an rclcpp client on rmw_fastrtps does: a
// std_srvs/srv/Trigger request on rq/NODE/save_mapRequest whose related sample identity names the
// client's reply reader, then the reply on rr/NODE/save_mapReply that names this request. Prints
// "success: true|false" and the message; exit 0 only for a matching, successful reply.
// Usage: ros2_save_map DOMAIN NODE
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/rtps/common/WriteParams.h>
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>

#include <chrono>
#include <cstring>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "ros2_wire.hpp"

namespace fdds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;
using mmlio::ros2::Cdr;

namespace {

/// Samples as raw CDR bytes under a ROS 2 type name (the tool's own, independent of dds_transport).
class RawType : public fdds::TopicDataType {
 public:
  explicit RawType(const std::string& name) {
    setName(name.c_str());
    m_typeSize = 1024;
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, rtps::SerializedPayload_t* payload) override {
    const Cdr& cdr = *static_cast<const Cdr*>(data);
    std::memcpy(payload->data, cdr.data(), cdr.size());
    payload->length = static_cast<std::uint32_t>(cdr.size());
    payload->encapsulation = CDR_LE;
    return true;
  }
  bool deserialize(rtps::SerializedPayload_t* payload, void* data) override {
    static_cast<Cdr*>(data)->assign(payload->data, payload->data + payload->length);
    return true;
  }
  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] { return static_cast<std::uint32_t>(static_cast<const Cdr*>(data)->size()); };
  }
  void* createData() override { return new Cdr(); }
  void deleteData(void* data) override { delete static_cast<Cdr*>(data); }
  bool getKey(void*, rtps::InstanceHandle_t*, bool) override { return false; }
};

}  // namespace

int main(int argc, char** argv) {
  using namespace mmlio::ros2;
  if (argc != 3) {
    std::cerr << "usage: ros2_save_map DOMAIN NODE\n";
    return 2;
  }
  const std::string service = std::string("/") + argv[2] + "/save_map";
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  fdds::DomainParticipant* p = factory->create_participant(std::stoi(argv[1]), fdds::PARTICIPANT_QOS_DEFAULT);
  const std::string request_type = typeOnWire("std_srvs/srv/Trigger_Request");
  const std::string reply_type = typeOnWire("std_srvs/srv/Trigger_Response");
  fdds::TypeSupport(new RawType(request_type)).register_type(p);
  fdds::TypeSupport(new RawType(reply_type)).register_type(p);
  fdds::Topic* rq = p->create_topic(requestTopicOnWire(service), request_type, fdds::TOPIC_QOS_DEFAULT);
  fdds::Topic* rr = p->create_topic(replyTopicOnWire(service), reply_type, fdds::TOPIC_QOS_DEFAULT);
  fdds::DataWriterQos wq = fdds::DATAWRITER_QOS_DEFAULT;  // services: reliable, volatile, keep last 10
  wq.history().depth = 10;
  fdds::DataReaderQos rqos = fdds::DATAREADER_QOS_DEFAULT;
  rqos.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  rqos.history().depth = 10;
  fdds::DataWriter* writer = p->create_publisher(fdds::PUBLISHER_QOS_DEFAULT)->create_datawriter(rq, wq);
  fdds::DataReader* reader = p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT)->create_datareader(rr, rqos);

  int code = 1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  const auto matched = [&] {
    fdds::PublicationMatchedStatus pub{};
    fdds::SubscriptionMatchedStatus sub{};
    writer->get_publication_matched_status(pub);
    reader->get_subscription_matched_status(sub);
    return pub.current_count > 0 && sub.current_count > 0;
  };
  while (!matched() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));

  Cdr request{0x00, 0x01, 0x00, 0x00, 0x00};  // Trigger_Request: one uint8 placeholder
  rtps::WriteParams params;
  params.related_sample_identity().writer_guid() = reader->guid();  // where rmw_fastrtps wants the reply
  if (!writer->write(&request, params)) {
    std::cerr << "ros2_save_map: cannot send the request\n";
  } else {
    const rtps::SampleIdentity sent = params.sample_identity();
    while (std::chrono::steady_clock::now() < deadline && code == 1) {
      Cdr reply;
      fdds::SampleInfo info;
      if (reader->take_next_sample(&reply, &info) != ReturnCode_t::RETCODE_OK) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        continue;
      }
      // rmw_fastrtps: a reply is ours when it names our reply reader and our request's number.
      if (!info.valid_data || info.related_sample_identity.writer_guid() != reader->guid() ||
          info.related_sample_identity.sequence_number() != sent.sequence_number())
        continue;
      eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(reply.data()), reply.size());
      eprosima::fastcdr::Cdr in(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
      in.read_encapsulation();
      bool success = false;
      std::string message;
      in >> success >> message;
      std::cout << "success: " << (success ? "true" : "false") << "\nmessage: " << message << "\n";
      code = success ? 0 : 3;
    }
    if (code == 1) std::cerr << "ros2_save_map: no reply within 60 s\n";
  }
  p->delete_contained_entities();
  factory->delete_participant(p);
  return code;
}
