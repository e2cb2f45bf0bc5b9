// Uses the installed headers and libraries: the default rig config, parsed back, and the version.
#include <iostream>

#include "mmlio/io/rig_config.hpp"
#include "mmlio/version.hpp"

int main() {
  const mmlio::io::RigConfig cfg = mmlio::io::parseRigConfig(mmlio::io::defaultConfigYaml(), "defaults");
  std::cout << "mmlio " << mmlio::kVersion << ": " << cfg.lidars.size() << " LiDARs, mode " << cfg.mode << "\n";
  return cfg.lidars.size() == 2 ? 0 : 1;
}
