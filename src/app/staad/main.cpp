// staad: the STAA* motion controller daemon (docs/staad.md).
//
//   staad [--config FILE] [--hal sim|socketcan|ros] [--socket PATH] [--telemetry FILE] [--svg FILE]
//         [NAME:=VALUE ...]
//
// NAME:=VALUE arguments are ROS remappings (roslaunch passes __name:=, __log:= and the
// launch file's remaps): they go to the ROS link, not to the option parser.
// Exit status: 0 stopped by SIGTERM/SIGINT, 1 run-time failure (socket busy, a thread could
// not start), 2 bad config, arguments or environment (the message names the key and value),
// 3 the hardware cannot be opened (no such CAN interface, no socket at the unix: path).
#include "app/staad/daemon.hpp"
#include "rt/clock.hpp"

#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  using namespace staa::staad;
  try {
    CLI::App app{"staad: the STAA* motion controller daemon (real-time, 30 Hz)"};
    std::string config;
    std::string hal;
    std::string socket;
    std::string telemetry;
    std::string svg;
    app.add_option("--config", config, "daemon config (default: config/staad.yaml, then /etc/staad/staad.yaml)");
    std::vector<std::string> hal_names;  // the config's names, parsed into the enum below
    for (const auto& choice : kHalBackends) hal_names.emplace_back(choice.name);
    app.add_option("--hal", hal, "hardware: sim (the simulator), socketcan or ros")->check(CLI::IsMember(hal_names));
    app.add_option("--socket", socket, "control socket path (overrides socket.path)");
    app.add_option("--telemetry", telemetry, "telemetry CSV file (overrides telemetry.path)");
    app.add_option("--svg", svg, "a picture of the run written when staad stops (overrides telemetry.svg)");
    std::vector<std::string> args;
    std::vector<std::string> remappings;
    for (int i = argc - 1; i >= 1; --i) {  // CLI11 takes them in reverse
      const std::string a = argv[i];
      (a.find(":=") != std::string::npos && a.rfind("-", 0) != 0 ? remappings : args).push_back(a);
    }
    try {
      app.parse(args);
    } catch (const CLI::ParseError& e) {
      const int code = app.exit(e);
      return code == 0 ? kExitOk : kExitBadConfig;
    }

    DaemonOptions options;
    options.config_file = config;
    if (!hal.empty()) options.hal = staa::io::valueOf<HalBackend>(kHalBackends, hal);
    if (!socket.empty()) options.socket_path = socket;
    if (!telemetry.empty()) options.telemetry_path = telemetry;
    if (!svg.empty()) options.svg_path = svg;
    options.ros_remappings.assign(remappings.rbegin(), remappings.rend());
    staa::rt::MonotonicClock clock;
    return runDaemon(options, clock, std::cerr);
  } catch (const std::exception& e) {
    std::cerr << "staad: " << e.what() << std::endl;
    return kExitFailure;
  } catch (...) {
    std::cerr << "staad: unknown error" << std::endl;
    return kExitFailure;
  }
}
