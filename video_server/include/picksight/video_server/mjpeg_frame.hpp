// An MJPEG frame as cameras send it, made into a JPEG any decoder reads: the
// standard Huffman tables put in when the frame has none, and whatever
// follows the end-of-image marker cut off.
#pragma once

#include <opencv2/core.hpp>

#include "picksight/common/result.hpp"

namespace picksight::video {

// `raw` is the frame's bytes as one continuous CV_8UC1 row. Motion JPEG
// (UVC webcams, the AVI1 convention, many HTTP servers of phone apps) leaves
// out the Huffman tables and expects the decoder to use the standard ones
// (ITU-T T.81 Annex K.3), which not every decoder does; servers also pad
// frames after the end marker (zeros, or stray bytes of a boundary). The
// result is a view of `raw` when it needed no tables, else a new buffer.
// Errors (SourceErrc::kBadValue, naming MJPEG) for a frame without start
// marker, without scan, or cut short (no end marker after the scan).
// Pure function; safe from any thread.
Result<cv::Mat> completeMjpegFrame(const cv::Mat& raw);

}  // namespace picksight::video
