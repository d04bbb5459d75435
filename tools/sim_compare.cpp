// stac sim-compare: how close simulated scans come to real ones (offline/sim_compare_job.hpp):
// the options, the summary.
#include <memory>
#include <string>

#include "offline/sim_compare_job.hpp"
#include "settings/build_tree.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"
#include "tools/support/terminal_output.hpp"

namespace stac::tools {

void add_sim_compare_command(CLI::App& app) {
  auto o = std::make_shared<offline::SimCompareJobOptions>();
  CLI::App* cmd =
      app.add_subcommand("sim-compare", "Compare simulated scans with real KITTI HDL-64E scans");
  cmd->description(
      "Compare simulated scans (a `stac sim` capture, decoded) with real KITTI HDL-64E scans:\n"
      "points per scan, points and elevation per ring, range histogram, ground fraction and\n"
      "intensity histogram, with the same rules on both. Writes DIR/realism.md, realism.json,\n"
      "charts and a bird's-eye picture of a simulated and a real scan at the same scale.");
  cmd->add_option("--sim", o->sim, "pcap written by `stac sim`")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--kitti", o->kitti,
                  "a KITTI .bin scan, a folder of them, or a KITTI raw drive folder")
      ->default_str(std::string(stac::settings::kSourceDir) + "/../shared/data/kitti");
  o->kitti = std::string(stac::settings::kSourceDir) + "/../shared/data/kitti";
  cmd->add_option("--report", o->report, "folder to write the report into")->required();
  cmd->add_option("--calib", o->calib, "calibration of the simulated unit (default: the config's)");
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->add_option("--mount-height", o->mount_height_m, "sensor height above the ground, m (both)")
      ->capture_default_str()
      ->check(finite_range(0.0, 10.0));
  cmd->add_option("--ground-margin", o->ground_margin_m, "ground: z below -mount height + this, m")
      ->capture_default_str()
      ->check(finite_range(-5.0, 5.0));
  cmd->add_option("--max-scans", o->max_scans, "simulated scans to use (0: all complete ones)")
      ->capture_default_str();
  cmd->callback([o] {
    TerminalOutput terminal;
    const rt::Status done = offline::run_sim_compare_job(*o, terminal.output());
    terminal.finish();
    if (!done) throw CLI::RuntimeError(fail(done.error().message));
  });
}

}  // namespace stac::tools
