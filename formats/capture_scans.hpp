// The complete scans of a capture, in order: its HDL-64E UDP packets (to velodyne.port) through
// a ScanStream with the config's framing. Shared by `stac segment` and `stac demo`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>

#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "rt/expected.hpp"
#include "settings/settings.hpp"

namespace stac::formats {

// Calls on_scan(scan) for each complete scan until it returns false; returns how many were passed
// (an error when the capture cannot be opened or holds no complete scan, saying why).
rt::Result<std::uint64_t> for_each_complete_scan(
    const std::filesystem::path& capture, const velodyne::Calibration& calibration,
    const settings::VelodyneSettings& settings,
    const std::function<bool(const velodyne::Scan&)>& on_scan);

}  // namespace stac::formats
