// Writing a picture of pictures as PNG (inside this folder only: it takes an OpenCV image).
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <vector>

#include "rt/expected.hpp"

namespace stac::pictures {

// Fails naming the file: unwritable (is the folder there?), or OpenCV's own error.
rt::Status write_png(const std::filesystem::path& png, const cv::Mat& img,
                     const std::vector<int>& params = {});

}  // namespace stac::pictures
