// Test tool: plays a ROS 1 bag into DDS as ROS 2 drivers would publish it: each message CDR-encoded
// as its ROS 2 type (the Livox topics as `LIVOX_TYPE`), on its topic's ROS 2 name, with the
// drivers' sensor-data QoS (best effort, keep last 5), at RATE times the bag's pace. Starts once
// every topic has a reader (the node), waits 30 s at most for them. TRANSPORT (dds_transport.hpp)
// is Fast DDS's default unless given: a driver on rmw_fastrtps without a profile. With PAUSE
// (TOPIC:FROM_S:SECONDS, several separated by commas), TOPIC's driver stops FROM_S seconds into the
// bag for SECONDS and then restarts: a new participant and writer (a new process would have them)
// publish the rest. With LOOP=N the bag is played N times, each pass with the bag's own stamps (as
// `rosbag play -l`: the clock goes back at every restart). With FROM=S the first pass starts S seconds
// into the bag (as `rosbag play -s S`: a node started after the drivers sees the rig in motion).
// Usage: [PAUSE=...] [LOOP=N] [FROM=S] ros2_play DOMAIN BAG RATE LIVOX_TYPE [udp|shm|default]
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "../../tests/io/ros2_twin.hpp"
#include "dds_transport.hpp"
#include "wait_for.hpp"

namespace {

struct Pause {
  std::string topic;
  double from_s = 0, seconds = 0;
};

std::vector<Pause> pausesFromEnv() {
  std::vector<Pause> pauses;
  const char* e = std::getenv("PAUSE");
  std::stringstream list(e ? e : "");
  for (std::string v; std::getline(list, v, ',');) {
    const auto b = v.rfind(':');
    const auto a = b == std::string::npos || b == 0 ? std::string::npos : v.rfind(':', b - 1);
    if (a == std::string::npos) throw std::runtime_error("PAUSE is TOPIC:FROM_S:SECONDS[,...]");
    pauses.push_back({v.substr(0, a), std::stod(v.substr(a + 1, b - a - 1)), std::stod(v.substr(b + 1))});
  }
  return pauses;
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
    const std::vector<Pause> pauses = pausesFromEnv();
    std::map<std::string, std::unique_ptr<DdsParticipant>> restarted;  // a paused topic's driver after its restart
    const char* loop_env = std::getenv("LOOP");
    const int passes = loop_env ? std::max(1, std::atoi(loop_env)) : 1;
    const char* from_env = std::getenv("FROM");
    const double from_s = from_env ? std::max(0.0, std::atof(from_env)) : 0.0;
    const std::uint64_t t0 = records.front().time_ns;
    const double bag_s = 1e-9 * static_cast<double>(records.back().time_ns - t0) + 0.1;
    const auto start = std::chrono::steady_clock::now();
    for (int pass = 0; pass < passes; ++pass) {
      for (const auto& r : records) {
        const double t = 1e-9 * static_cast<double>(r.time_ns - t0);
        if (pass == 0 && t < from_s) continue;
        const auto paused = std::find_if(pauses.begin(), pauses.end(),
                                         [&](const Pause& p) { return p.topic == r.topic && t >= p.from_s; });
        if (pass == 0 && paused != pauses.end()) {
          if (t < paused->from_s + paused->seconds) continue;
          if (!restarted.count(r.topic)) {
            auto& driver = restarted[r.topic] =
                std::make_unique<DdsParticipant>(domain, "ros2_play_restarted", transport);
            writers[r.topic] = &driver->writer(topicOnWire(r.topic), typeOnWire(r.type), sensorDataQos());
            std::cerr << "ros2_play: " << r.topic << " restarted after " << paused->seconds << " s\n";
          }
        }
        const double due_s = (pass * bag_s + t - from_s) / rate;
        std::this_thread::sleep_until(start + std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 * due_s)));
        if (!writers[r.topic]->write(r.cdr)) std::cerr << "ros2_play: DDS refused a message on " << r.topic << "\n";
      }
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));  // best effort: let the last ones leave
    std::cout << "played " << records.size() * static_cast<std::size_t>(passes) << " messages on " << writers.size()
              << " topics\n";
  } catch (const std::exception& e) {
    std::cerr << "ros2_play: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
