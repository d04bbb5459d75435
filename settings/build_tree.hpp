// The source and build folders of this build and ../shared/data (settings/build_tree.cpp.in, made
// by CMake), for defaults that point into the source tree while a binary runs from its build
// folder. Only that one generated file holds the paths, so every other file compiles alike in a
// clone at any path (ccache shares them; .ci/run).
#pragma once

namespace stac::settings {

extern const char* const kSourceDir;      // absolute, no trailing slash
extern const char* const kBinaryDir;      // absolute, no trailing slash
extern const char* const kSharedDataDir;  // ../shared/data beside the source tree

}  // namespace stac::settings
