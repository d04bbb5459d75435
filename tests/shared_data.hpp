// Where the tests find ../shared/data, and a skip that says why when it is absent.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace stac::testing {

inline std::filesystem::path shared_data(const std::string& relative) {
  return std::filesystem::path(STAC_SHARED_DATA_DIR) / relative;
}

}  // namespace stac::testing

// Skips the current test, naming the missing file, when shared/data is not beside the checkout.
#define STAC_REQUIRE_SHARED_DATA(relative_path)                                             \
  do {                                                                                      \
    if (!std::filesystem::exists(::stac::testing::shared_data(relative_path))) {            \
      GTEST_SKIP() << "SKIPPED: " << ::stac::testing::shared_data(relative_path)            \
                   << " is absent (shared/data must sit beside the checkout)";              \
    }                                                                                       \
  } while (0)
