// mmlio: multi-modal multi-LiDAR-inertial odometry and mapping, command-line front end.
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/version.hpp"

int main(int argc, char** argv) {
  CLI::App app{"mmlio: multi-LiDAR-inertial odometry and mapping for ROS 1 and ROS 2 bags"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("mmlio ") + mmlio::kVersion + " (" + mmlio::kCommit + ")");
  bool verbose = false, quiet = false;
  app.add_flag("-v,--verbose", verbose, "Print debug messages");
  app.add_flag("-q,--quiet", quiet, "Print warnings and errors only");
  app.parse_complete_callback([&] {
    mmlio::log::configure(verbose ? mmlio::log::Level::kDebug
                                  : (quiet ? mmlio::log::Level::kWarn : mmlio::log::Level::kInfo));
  });

  mmlio::apps::registerInfoCommand(app);
  mmlio::apps::registerInitCommand(app);
  mmlio::apps::registerSimulateCommand(app);
  mmlio::apps::registerRunCommand(app);
  mmlio::apps::registerLocalizeCommand(app);
  mmlio::apps::registerEvaluateCommand(app);
  mmlio::apps::registerBenchCommand(app);
  mmlio::apps::registerCalibrateCommand(app);
  mmlio::apps::registerConfigCommand(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" with code 0; every usage error is one line and exit 1, as
    // the README documents (CLI11's own codes, 105 and up, are not).
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::cerr << "mmlio: " << e.what() << " (see mmlio --help)\n";
    return 1;
  } catch (const mmlio::Error& e) {
    std::cerr << "mmlio: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "mmlio: internal error: " << e.what() << '\n';
    return 2;
  }
  return 0;
}
