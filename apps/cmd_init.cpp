// mmlio init BAG: a starter rig config from the bag's topics (see io::starterRigConfig).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/io/bag_info.hpp"
#include "mmlio/io/rig_starter.hpp"

namespace mmlio::apps {
namespace {

struct InitArgs {
  std::string bag, out;
  bool force = false;
};

void init(const InitArgs& a) {
  if (!a.out.empty() && !a.force && std::filesystem::exists(a.out))
    throw Error(a.out + " exists: give another --out, or --force to replace it");
  const std::string text = io::starterRigConfig(io::describeBag(a.bag));
  if (a.out.empty()) {
    std::cout << text;
    return;
  }
  {
    std::ofstream file(a.out);
    if (!(file << text)) throw Error("cannot write " + a.out);
  }
  std::printf(
      "written: %s\n"
      "next: read the lines marked CHECK, then\n"
      "  mmlio config %s                                   # checks it\n"
      "  mmlio calibrate %s --config %s --out calib.yaml   # a still start, then turns\n"
      "  mmlio run %s --config %s --calib calib.yaml --out out\n",
      a.out.c_str(), a.out.c_str(), a.bag.c_str(), a.out.c_str(), a.bag.c_str(), a.out.c_str());
}

}  // namespace

void registerInitCommand(CLI::App& app) {
  auto args = std::make_shared<InitArgs>();
  CLI::App* cmd =
      app.add_subcommand("init", "A starter rig config from a bag: topics, LiDAR types, mode, what to check");
  cmd->add_option("bag", args->bag, "ROS 1 .bag, ROS 2 .mcap, rosbag2 folder or .db3 recorded on the rig")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("-o,--out", args->out, "Write the config here (default: print it)");
  cmd->add_flag("--force", args->force, "Replace --out if it exists");
  cmd->callback([args] { init(*args); });
}

}  // namespace mmlio::apps
