#pragma once
// A ROS 2 node's presence on DDS, through Debian's Fast DDS (the default RMW of Humble and Jazzy):
// one domain participant, writers and readers of ROS 2 topics whose samples are the messages'
// serialised CDR (ros2_wire.hpp), under ROS 2's wire names and with the QoS ROS 2 profiles map to.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ros2_wire.hpp"

namespace mmlio::ros2 {

/// The QoS policies the node's endpoints differ in (rmw_fastrtps maps ROS 2's profiles to DDS
/// one to one: reliability, durability, history keep-last depth).
struct Qos {
  bool reliable = true;
  bool transient_local = false;  // late joiners get the last `depth` samples (ROS 1's latch)
  int depth = 10;
};
/// rclcpp::SensorDataQoS: best effort, volatile, keep last 5 (what LiDAR and IMU drivers publish with).
Qos sensorDataQos();
/// rclcpp::QoS(depth): reliable, volatile.
Qos reliableQos(int depth = 10);
/// A map or path for late joiners: reliable, transient local, keep last 1.
Qos latchedQos();

/// Which request a service reply answers: the writer GUID and sequence number rmw_fastrtps clients
/// match their replies by.
struct SampleIdentity {
  std::array<std::uint8_t, 16> writer_guid{};
  std::int32_t sequence_high = 0;
  std::uint32_t sequence_low = 0;
};

/// How the participant's samples travel. Fast DDS's defaults, which rmw_fastrtps uses without a
/// profile, lose large best-effort samples: a 0.9 MB cloud leaves as a burst of 64 KB fragments,
/// more than a 512 KB shared-memory segment or the kernel's default 208 KB UDP receive buffer
/// holds, and a sample missing one fragment is lost whole.
struct Transport {
  enum class Kind {
    kFastDdsDefault,  // shared memory and UDP as Fast DDS ships them (what a driver on defaults uses)
    kUdp,             // UDP only, with socket buffers that hold bursts of large samples
    kSharedMemory,    // shared memory with a large segment, UDP as kUdp for other hosts
  };
  Kind kind = Kind::kUdp;
  std::uint32_t socket_buffer_bytes = 8u << 20;  // asked of the kernel, which caps it at net.core.rmem_max
  std::uint32_t shm_segment_bytes = 32u << 20;   // what this participant's writers may have in flight
};

/// "udp", "shm" or "default" (Fast DDS's own); throws mmlio::Error naming the choices otherwise.
Transport::Kind transportKind(const std::string& name);

/// The receive buffer the kernel grants a UDP socket that asks for `bytes` (net.core.rmem_max
/// caps it; 0 if that cannot be read).
std::uint32_t grantedReceiveBuffer(std::uint32_t bytes);

class DdsParticipant {
 public:
  /// Joins DDS domain `domain_id` (ROS_DOMAIN_ID; 0-232). Throws mmlio::Error if DDS refuses.
  explicit DdsParticipant(int domain_id, const std::string& name = "mmlio", const Transport& transport = Transport());
  ~DdsParticipant();
  DdsParticipant(const DdsParticipant&) = delete;
  DdsParticipant& operator=(const DdsParticipant&) = delete;

  class Writer {
   public:
    virtual ~Writer() = default;
    /// Sends one serialised message (false if DDS refused it).
    virtual bool write(const Cdr& message) = 0;
    /// Sends a service reply answering `request` (its related sample identity).
    virtual bool writeReply(const Cdr& reply, const SampleIdentity& request) = 0;
    /// Readers currently matched (discovered, with compatible QoS).
    virtual int matched() const = 0;
  };
  using OnMessage = std::function<void(Cdr&& message)>;
  using OnRequest = std::function<void(Cdr&& request, const SampleIdentity& identity)>;

  /// A writer of `wire_topic` ("rt/..."), samples of `wire_type` ("pkg::msg::dds_::Type_"). The
  /// participant owns it.
  Writer& writer(const std::string& wire_topic, const std::string& wire_type, const Qos& qos);
  /// Calls on_message on DDS's listener thread for every sample received.
  void reader(const std::string& wire_topic, const std::string& wire_type, const Qos& qos, OnMessage on_message);
  /// A reader of service requests: each comes with the identity its reply must carry. As
  /// rmw_fastrtps serves them: the request's own identity, its writer GUID replaced by the one the
  /// client names in the request's related sample identity (its reply reader), when it names one.
  void requestReader(const std::string& wire_topic, const std::string& wire_type, const Qos& qos, OnRequest on_request);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// ROS_DOMAIN_ID from the environment (0 if unset); throws mmlio::Error if it is not 0-232.
int domainIdFromEnvironment();

}  // namespace mmlio::ros2
