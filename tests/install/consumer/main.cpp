// Uses the installed headers and libraries: the default rig config, parsed back, and the version.
#include <iostream>

#include "mmlio/config/rig_config.hpp"
#include "mmlio/version.hpp"

int main() {
  const mmlio::config::RigConfig cfg = mmlio::config::parseRigConfig(mmlio::config::defaultConfigYaml(), "defaults");
  std::cout << "mmlio " << mmlio::kVersion << ": " << cfg.lidars.size() << " LiDARs, mode " << cfg.mode << "\n";
  return cfg.lidars.size() == 2 ? 0 : 1;
}
