// mmlio config: every rig-config key with its documentation and default (--dump-defaults), or a
// rig file checked and printed as it will be run, defaults filled in.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/error.hpp"

namespace mmlio::apps {
namespace {

struct ConfigArgs {
  std::string file;
  bool dump_defaults = false;
};

void config(const ConfigArgs& a) {
  if (a.dump_defaults == !a.file.empty())
    throw Error("give either --dump-defaults or a rig config file to check (mmlio config --help)");
  if (a.dump_defaults) {
    std::cout << config::defaultConfigYaml();
    return;
  }
  const config::RigConfig cfg = config::loadRigConfig(a.file);  // throws with file, line and key on a mistake
  std::cout << "# " << a.file << " as mmlio runs it: every key, defaults filled in\n" << config::toYaml(cfg);
}

}  // namespace

void registerConfigCommand(CLI::App& app) {
  auto args = std::make_shared<ConfigArgs>();
  CLI::App* cmd = app.add_subcommand(
      "config", "Print every rig-config key with its meaning and default, or check a rig file and print it in full");
  cmd->add_flag("--dump-defaults", args->dump_defaults,
                "Every key with its documentation and default value (a starting point for a rig file)");
  cmd->add_option("file", args->file, "A rig config to check: printed with every default filled in")
      ->check(CLI::ExistingFile);
  cmd->callback([args] { config(*args); });
}

}  // namespace mmlio::apps
