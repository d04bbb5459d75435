// stac-node: the live component alone, as the vehicle runs it (deploy/stac.service): the
// configuration file says everything; SIGINT/SIGTERM stop it (with a summary on stderr), SIGHUP
// reloads the model. `stac run` is the same component with options for people.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <new>
#include <set>
#include <string>

#include "runtime/component.hpp"
#include "settings/run_settings.hpp"
#include "settings/settings.hpp"
#include "stac_version.hpp"

int main(int argc, char** argv) try {
  CLI::App app{
      "stac-node - the STAC live component: Velodyne UDP, INS and CAN in; segmented, tracked\n"
      "and classified objects and health out on DDS (docs/run.md). Everything comes from the\n"
      "configuration file; `stac run --help` has the same component with overrides.",
      "stac-node"};
  std::string config;
  double seconds = 0;
  app.add_option("--config", config, stac::settings::kConfigOptionHelp);
  app.add_option("--seconds", seconds, "stop after this many seconds (default: run until stopped)")
      ->check(CLI::Range(0.0, 1e9));
  bool check = false;
  app.add_flag(
      "--check", check,
      "load the configuration and every file it names (calibration, model, DBC), check its\n"
      "addresses (one this machine has) and the CAN interface, create the DDS domain with its\n"
      "Cyclone XML (and no participant: nothing is announced; with DDS Security one, deleted at\n"
      "once, as only that shows whether Cyclone takes the identity), say what was loaded and\n"
      "exit: 0 when the service can start with it");
  bool cpu_affinity = false;
  app.add_flag("--cpu-affinity", cpu_affinity,
               "print the CPUs the config pins threads to (run.<thread>_cpu), as systemd's\n"
               "CPUAffinity= takes them, and exit (the stac-cpu-affinity systemd generator)");
  app.set_version_flag("--version", std::string("stac-node ") + STAC_VERSION_LINE);
  CLI11_PARSE(app, argc, argv);
  if (cpu_affinity) {
    auto run = stac::settings::load_run_settings(stac::settings::config_path(config));
    if (!run) {
      std::fprintf(stderr, "stac-node: %s\n", run.error().message.c_str());
      return 1;
    }
    std::set<int> cpus;
    for (const auto* t : {&run->receiver, &run->perception, &run->publisher, &run->pose})
      if (t->cpu >= 0) cpus.insert(t->cpu);
    std::string list;
    for (const int c : cpus) list += (list.empty() ? "" : " ") + std::to_string(c);
    if (!list.empty()) std::printf("%s\n", list.c_str());
    return 0;
  }
  auto settings = stac::runtime::load_component_settings(stac::settings::config_path(config));
  if (!settings) {
    std::fprintf(stderr, "stac-node: %s\n", settings.error().message.c_str());
    return 1;
  }
  settings->name = "stac-node";
  if (check) {
    auto files =
        stac::runtime::check_component_files(*settings, stac::settings::config_path(config));
    if (!files) {
      std::fprintf(stderr, "stac-node: %s\n", files.error().message.c_str());
      return 1;
    }
    std::printf("stac-node: %s is complete: %s\n",
                stac::settings::config_path(config).string().c_str(), files->c_str());
    return 0;
  }
  settings->stop_after_s = seconds;
  auto component = stac::runtime::Component::create(*settings);
  if (!component) {
    std::fprintf(stderr, "stac-node: %s\n", component.error().message.c_str());
    return 1;
  }
  stac::runtime::run_with_signals(**component);
  stac::runtime::print_summary((*component)->summary(), settings->name, stderr);
  return 0;
} catch (const std::bad_alloc&) {
  std::fprintf(stderr, "stac-node: %s\n", stac::settings::kOutOfMemoryAtStartUp);
  return 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "stac-node: %s\n", e.what());
  return 1;
} catch (...) {
  std::fprintf(stderr, "stac-node: stopped by an unknown exception\n");
  return 1;
}
