// `stac sim`'s job as `stac demo` runs it too: sim::write_drive with its summary on stderr and a
// progress bar.
#pragma once

#include "sim/drive_writer.hpp"

namespace stac::tools {

// Returns the process exit code (0 ok, 1 with a message printed).
int run_sim(const sim::DriveOptions& options);

}  // namespace stac::tools
