#pragma once
// Polls a condition a DDS test waits on (discovery, delivery) until it holds or time runs out.
#include <chrono>
#include <thread>

namespace mmlio::ros2 {

template <class Pred> bool waitFor(Pred pred, double seconds) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!pred()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

}  // namespace mmlio::ros2
