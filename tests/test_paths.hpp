// Where a test finds the source tree, the build tree, ../shared/data and the programs it runs.
// Read at run time from the build tree's stac_test_paths.txt (tests/CMakeLists.txt writes it),
// found by walking up from the test executable, so no test compiles a path in: a clone at another
// path compiles to the same objects and ccache shares them (.ci/run). A missing or incomplete file
// stops the test program at once, saying which.
#pragma once

namespace stac::testing {

const char* source_dir();       // the repository root
const char* binary_dir();       // the build tree's root
const char* shared_data_dir();  // ../shared/data beside the repository
const char* stac_cli();         // the `stac` binary
const char* stac_node();        // the `stac-node` binary
const char* c_subscriber();     // examples/c_subscriber's binary

}  // namespace stac::testing
