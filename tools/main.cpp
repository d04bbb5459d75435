// stac: one binary, one subcommand per job. `stac --help` lists them; `stac <sub> --help` explains
// each one.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <new>

#include "pictures/drawing.hpp"
#include "settings/settings.hpp"
#include "stac_version.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"

namespace stac::tools {

int fail(const std::string& message) {
  std::fprintf(stderr, "stac: %s\n", message.c_str());
  return 1;
}

CLI::Option* needs_pictures(CLI::Option* option) {
  return option->check(CLI::Validator(
      [](const std::string&) -> std::string {
        if (pictures::pictures_built()) return "";
        return std::string("this stac was built without pictures (") +
               pictures::kWithoutPicturesHint + ")";
      },
      "", "pictures"));
}

}  // namespace stac::tools

int main(int argc, char** argv) try {
  CLI::App app{
      "stac - segmentation, tracking and classification of Velodyne HDL-64E scans.\n"
      "Decodes sensor packets (live UDP or pcap) into calibrated, timed 360-degree scans.\n"
      "Configuration: config/stac.yaml (or --config / $STAC_CONFIG).",
      "stac"};
  app.set_version_flag("--version", std::string("stac ") + STAC_VERSION_LINE,
                       "print the version and the git commit it was built from, and exit");
  app.require_subcommand(1);
  app.footer(
      "Examples:\n"
      "  stac demo                                   # a simulated drive, live over loopback to "
      "DDS\n"
      "  stac decode --calib db.xml --in run.pcap --out run.csv\n"
      "  stac decode --calib db.xml --in run.pcap --out scans/ --format kitti\n"
      "  stac record --out live.pcap --duration 10   # capture the sensor's UDP stream\n"
      "  stac sim --scenario urban --seed 7 --duration 30 --out run.pcap --truth run.truth.jsonl\n"
      "  stac status --in run.pcap --calib-out unit.yaml   # the calibration the sensor sends\n"
      "  stac candump --in drive.log --out odometry.csv  # vehicle speed and yaw rate from CAN\n"
      "  stac replay --in run.pcap --rate 1          # send it again over loopback UDP\n"
      "  stac eval --truth run.truth.jsonl --tracks run.tracks.jsonl --report eval/  # metrics\n"
      "  stac segment --in scan.bin --out segments.csv --png bev.png  # obstacles of one scan\n"
      "  stac process run.pcap --truth run.truth.jsonl --tracks run.tracks.jsonl  # segment+track\n"
      "  stac echo tracked_objects --count 10        # print what arrives on a DDS topic\n"
      "  stac view                                   # the DDS topics live in Foxglove\n"
      "  stac dataset --in run.pcap --truth run.truth.jsonl --out data/  # labelled tracks\n"
      "  stac train --data data/ --out model.stac  # track classifier\n"
      "  stac induct --state teach/ --classes car,pedestrian,bicyclist --labels data/ \\\n"
      "      --labels-per-class 5 --background empty/ --unlabeled drive1/  # group induction\n"
      "  stac label --state teach/                   # answer its questions on a web page\n"
      "  stac eval --classes --data test/ --model model.stac --report cls/  # Table 1.2\n"
      "  stac run --seconds 60                       # live: sensor UDP -> perception -> DDS\n"
      "Run 'stac <command> --help' for the options of each command.");
  stac::tools::add_decode_command(app);
  stac::tools::add_record_command(app);
  stac::tools::add_demo_command(app);
  stac::tools::add_sim_command(app);
  stac::tools::add_status_command(app);
  stac::tools::add_candump_command(app);
  stac::tools::add_replay_command(app);
  stac::tools::add_sim_compare_command(app);
  stac::tools::add_eval_command(app);
  stac::tools::add_segment_command(app);
  stac::tools::add_process_command(app);
  stac::tools::add_echo_command(app);
  stac::tools::add_run_command(app);
  stac::tools::add_dataset_command(app);
  stac::tools::add_train_command(app);
  stac::tools::add_induct_command(app);
  stac::tools::add_label_command(app);
  stac::tools::add_kitti_objects_command(app);
  stac::tools::add_view_command(app);
  stac::tools::refuse_bad_numbers(app);
  // `stac nosuch --help` would print the main help and exit 0: an unknown command is named first.
  if (argc > 1 && argv[1][0] != '-') {
    bool known = false;
    std::string names;
    for (const CLI::App* sub : app.get_subcommands({})) {
      known = known || sub->get_name() == argv[1];
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::fprintf(stderr, "stac: unknown command '%s'; the commands are: %s (stac --help)\n",
                   argv[1], names.c_str());
      return 2;
    }
  }
  // What escapes a subcommand is reported, never an abort: start-up allocates every capacity of
  // the configuration, and a machine without the memory for them gets told so.
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "stac: %s\n", stac::settings::kOutOfMemoryAtStartUp);
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stac: %s\n", e.what());
    return 1;
  }
  return 0;
} catch (const std::exception& e) {  // building the command line itself failed
  std::fprintf(stderr, "stac: %s\n", e.what());
  return 1;
} catch (...) {
  std::fprintf(stderr, "stac: stopped by an unknown exception\n");
  return 1;
}
