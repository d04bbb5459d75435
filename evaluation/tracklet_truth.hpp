// A KITTI raw drive's labels as the truth `stac eval` scores against (issue 33): its
// tracklet_labels.xml placed in the world by the drive's own poses (OXTS and mounting, as
// `stac process` places the drive's scans), one truth scan per scan of the drive.
#pragma once

#include <filesystem>
#include <vector>

#include "evaluation/tracks_jsonl.hpp"
#include "rt/expected.hpp"
#include "settings/settings.hpp"

namespace stac::evaluation {

// Per scan of the drive (its time; a one-instant sweep): every labelled object of a scored type
// (formats::stac_class_of_kitti_type: Misc and DontCare left out) at that frame, its box centre
// and yaw in the local ENU world anchored at the drive's first OXTS record (the truth's origin),
// its size, its velocity from the neighbouring frames, and the drive's points inside its box.
// Fails, naming the file, when the tracklets do not read, the drive has no oxts/, or a pose
// names a frame the drive does not have.
rt::Result<std::vector<TruthScanRecord>> truth_from_tracklets(
    const std::filesystem::path& tracklets, const std::filesystem::path& drive,
    settings::EgoSettings ego);

}  // namespace stac::evaluation
