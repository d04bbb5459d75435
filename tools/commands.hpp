// The `stac` subcommands. Each registers itself on the CLI11 app; main() only composes them.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace stac::tools {

void add_decode_command(CLI::App& app);
void add_record_command(CLI::App& app);
void add_demo_command(CLI::App& app);
void add_sim_command(CLI::App& app);
void add_status_command(CLI::App& app);
void add_candump_command(CLI::App& app);
void add_eval_command(CLI::App& app);
void add_segment_command(CLI::App& app);
void add_process_command(CLI::App& app);
// `stac decode applanix`, a subcommand of `decode`; returns it so decode can tell it was used.
CLI::App* add_decode_applanix_command(CLI::App& decode);
void add_replay_command(CLI::App& app);
void add_sim_compare_command(CLI::App& app);
void add_echo_command(CLI::App& app);
void add_run_command(CLI::App& app);
void add_dataset_command(CLI::App& app);
void add_train_command(CLI::App& app);
void add_induct_command(CLI::App& app);
void add_label_command(CLI::App& app);
void add_kitti_objects_command(CLI::App& app);
void add_view_command(CLI::App& app);

// Marks an option that asks for a picture (--png): in a build without pictures
// (-DSTAC_PICTURES=OFF) it is refused before any work, saying how to get them.
CLI::Option* needs_pictures(CLI::Option* option);

// Prints "stac: <message>" on stderr and returns the exit code 1, for command callbacks.
int fail(const std::string& message);

}  // namespace stac::tools
