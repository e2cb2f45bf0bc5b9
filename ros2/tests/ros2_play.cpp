// Test tool: plays a ROS 1 bag into DDS as ROS 2 drivers would publish it: each message CDR-encoded
// as its ROS 2 type (the Livox topics as `LIVOX_TYPE`), on its topic's ROS 2 name, with the
// drivers' sensor-data QoS (best effort, keep last 5), at RATE times the bag's pace. Starts once
// every topic has a reader (the node), waits 30 s at most for them. TRANSPORT (dds_transport.hpp)
// is Fast DDS's default unless given: a driver on rmw_fastrtps without a profile. With PAUSE
// (TOPIC:FROM_S:SECONDS), TOPIC's driver stops FROM_S seconds into the bag for SECONDS and then
// restarts: a new participant and writer (a new process would have them) publish the rest.
// Usage: [PAUSE=TOPIC:FROM_S:SECONDS] ros2_play DOMAIN BAG RATE LIVOX_TYPE [udp|shm|default]
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "../../tests/io/ros2_twin.hpp"
#include "dds_transport.hpp"
#include "wait_for.hpp"

namespace {

struct Pause {
  std::string topic;  // empty: none
  double from_s = 0, seconds = 0;
};

Pause pauseFromEnv() {
  Pause p;
  const char* e = std::getenv("PAUSE");
  if (!e || !*e) return p;
  const std::string v = e;
  const auto a = v.rfind(':', v.rfind(':') - 1), b = v.rfind(':');
  if (a == std::string::npos || b == std::string::npos) throw std::runtime_error("PAUSE is TOPIC:FROM_S:SECONDS");
  p.topic = v.substr(0, a);
  p.from_s = std::stod(v.substr(a + 1, b - a - 1));
  p.seconds = std::stod(v.substr(b + 1));
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace mmlio::ros2;
  if (argc != 5 && argc != 6) {
    std::cerr << "usage: ros2_play DOMAIN BAG RATE LIVOX_TYPE [udp|shm|default]\n";
    return 2;
  }
  try {
    const int domain = std::stoi(argv[1]);
    const double rate = std::stod(argv[3]);
    const auto records = mmlio::testing::ros2Records(argv[2], argv[4]);
    if (records.empty() || !(rate > 0)) throw std::runtime_error("nothing to play");
    Transport transport;
    transport.kind = transportKind(argc == 6 ? argv[5] : "default");
    DdsParticipant player(domain, "ros2_play", transport);
    std::map<std::string, DdsParticipant::Writer*> writers;
    for (const auto& r : records)
      if (!writers.count(r.topic))
        writers[r.topic] = &player.writer(topicOnWire(r.topic), typeOnWire(r.type), sensorDataQos());
    const bool matched = waitFor(
        [&] {
          for (const auto& [topic, w] : writers)
            if (w->matched() == 0) return false;
          return true;
        },
        30.0);
    if (!matched) throw std::runtime_error("the node's readers did not appear within 30 s");
    std::this_thread::sleep_for(std::chrono::seconds(1));  // discovery settles on both sides
    const Pause pause = pauseFromEnv();
    std::unique_ptr<DdsParticipant> restarted;  // the paused topic's driver after its restart
    const auto start = std::chrono::steady_clock::now();
    const std::uint64_t t0 = records.front().time_ns;
    for (const auto& r : records) {
      const double t = 1e-9 * static_cast<double>(r.time_ns - t0);
      if (r.topic == pause.topic && t >= pause.from_s) {
        if (t < pause.from_s + pause.seconds) continue;
        if (!restarted) {
          restarted = std::make_unique<DdsParticipant>(domain, "ros2_play_restarted", transport);
          writers[r.topic] = &restarted->writer(topicOnWire(r.topic), typeOnWire(r.type), sensorDataQos());
          std::cerr << "ros2_play: " << r.topic << " restarted after " << pause.seconds << " s\n";
        }
      }
      std::this_thread::sleep_until(start + std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 * t / rate)));
      if (!writers[r.topic]->write(r.cdr)) std::cerr << "ros2_play: DDS refused a message on " << r.topic << "\n";
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));  // best effort: let the last ones leave
    std::cout << "played " << records.size() << " messages on " << writers.size() << " topics\n";
  } catch (const std::exception& e) {
    std::cerr << "ros2_play: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
