// Image files and video streams through OpenCV's imgcodecs and videoio,
// loaded when a process first needs them rather than when it starts.
//
// Debian's imgcodecs brings GDAL, GDCM, OpenEXR and about 120 libraries
// more, and videoio FFmpeg and GStreamer: linked into a program, they cost
// every start about 115 ms of CPU (imgcodecs) and 85 ms more (videoio) in
// the dynamic loader, the kernel's mappings and their static constructors,
// whether or not the program ever reads a file (picksight-cam 131 ms against
// 11 ms for a tool without them, `perf stat ... --help`). Here they live in a
// module (libpicksight_codecs.so, beside the programs in ../lib/picksight)
// that is opened on the first call of a function below.
//
// Each function does what OpenCV's function of the same name does, with the
// same arguments and results. A module that cannot be opened throws
// std::runtime_error naming its path and the loader's reason: a broken
// installation, not a bad file, and never an empty image that would read as
// one. The enums (cv::IMREAD_*, cv::IMWRITE_*, cv::CAP_*) come from OpenCV's
// headers, included here.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>  // the cv::CAP_* enums

namespace picksight::codecs {

cv::Mat imread(const std::string& path, int flags = cv::IMREAD_COLOR);
bool imwrite(const std::string& path, cv::InputArray image, const std::vector<int>& params = {});
cv::Mat imdecode(cv::InputArray bytes, int flags);
bool imencode(const std::string& ext, cv::InputArray image, std::vector<uchar>& bytes,
              const std::vector<int>& params = {});
bool haveImageWriter(const std::string& path);

// A video stream read by OpenCV's cv::VideoCapture inside the module. The
// interface is PickSight's own, not cv::VideoCapture's, so that a program
// needs nothing of videoio to call it (UBSan's checks of a call through a
// pointer need the class's type information, which videoio would define).
// Each member does what cv::VideoCapture's member of the same name does.
class VideoStream {
 public:
  virtual ~VideoStream() = default;
  virtual bool open(const std::string& url, int api, const std::vector<int>& params) = 0;
  virtual bool isOpened() const = 0;
  virtual bool grab() = 0;
  virtual bool retrieve(cv::Mat& image) = 0;
  virtual double get(int property) const = 0;
  virtual bool set(int property, double value) = 0;
};

// A stream not yet opened.
std::unique_ptr<VideoStream> newVideoStream();

// Where the module is looked for: <directory of this executable>/../lib/
// picksight/libpicksight_codecs.so (build/bin and build/tests find build/lib;
// /usr/bin finds /usr/lib/picksight).
std::string modulePath();

}  // namespace picksight::codecs
