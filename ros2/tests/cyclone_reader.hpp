#pragma once
// Test helpers: a Cyclone DDS participant and readers of ROS 2 topics as the C types Cyclone's idlc
// generated from ROS 2's message definitions (idl/ros2_messages.idl): the ROS 2 peer of the tests.
#include <dds/dds.h>

#include <string>

namespace mmlio::ros2 {

/// A Cyclone DDS reader of one ROS 2 topic, taking samples of the generated C type T.
template <class T> class CycloneReader {
 public:
  CycloneReader(dds_entity_t participant, const dds_topic_descriptor_t* type, const std::string& wire_topic,
                bool transient_local = false) {
    topic_ = dds_create_topic(participant, type, wire_topic.c_str(), nullptr, nullptr);
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 100);
    if (transient_local) dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
    reader_ = dds_create_reader(participant, topic_, qos, nullptr);
    dds_delete_qos(qos);
  }
  bool ok() const { return topic_ > 0 && reader_ > 0; }
  /// Takes what arrived, calling f(const T&) for each valid sample; returns how many.
  template <class F> int take(F&& f) {
    constexpr int kMax = 64;
    void* samples[kMax] = {nullptr};
    dds_sample_info_t infos[kMax];
    const int n = dds_take(reader_, samples, infos, kMax, kMax);
    int valid = 0;
    for (int i = 0; i < n; ++i)
      if (infos[i].valid_data) {
        f(*static_cast<const T*>(samples[i]));
        ++valid;
      }
    if (n > 0) dds_return_loan(reader_, samples, n);
    return valid;
  }

 private:
  dds_entity_t topic_ = 0, reader_ = 0;
};

struct CycloneParticipant {
  explicit CycloneParticipant(int domain)
      : id(dds_create_participant(static_cast<dds_domainid_t>(domain), nullptr, nullptr)) {}
  ~CycloneParticipant() {
    if (id > 0) dds_delete(id);
  }
  dds_entity_t id;
};

}  // namespace mmlio::ros2
