// The filmstrip's PNG: the frame's rows stored without filtering or
// compression (deflate's "stored" blocks), a valid lossless PNG that every
// reader decodes, made in about the time of a copy. OpenCV's PNG writer
// always filters the rows, which alone costs 20 times that at 1920x1080:
// on a two-core cell it was the one cost recording put on LOCATE.
#pragma once

#include <optional>
#include <string>

#include <opencv2/core.hpp>

namespace picksight::filmstrip {

// 8-bit grey or BGR `image` as PNG bytes; nullopt for another type or a
// libpng failure.
std::optional<std::string> storedPng(const cv::Mat& image);

}  // namespace picksight::filmstrip
