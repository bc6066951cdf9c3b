// File camera source.
#include "file_source.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <opencv2/imgcodecs.hpp>

#include "eight_bit_image.hpp"

namespace picksight::video {

FileSource::FileSource(std::string path) : path_(std::move(path)) {}

Result<void> FileSource::open() { return refresh(); }

void FileSource::close() {
  image_.release();
  inode_ = 0;
  size_ = -1;
}

SourceInfo FileSource::info() const {
  SourceInfo i;
  i.vendor = "PickSight";
  i.model = "file";
  i.serial = path_;
  i.sensor_width = image_.cols;
  i.sensor_height = image_.rows;
  i.formats = {image_.channels() == 3 ? "BGR8" : "Mono8"};
  return i;
}

Result<void> FileSource::refresh() {
  struct stat st {};
  if (::stat(path_.c_str(), &st) != 0) {
    if (!image_.empty()) return {};  // keep serving the last image while the file is being replaced
    return makeError(SourceErrc::kUnavailable, "file:" + path_ + ": " + std::strerror(errno));
  }
  if (!image_.empty() && st.st_ino == inode_ && st.st_size == size_ &&
      st.st_mtim.tv_sec == mtime_.tv_sec && st.st_mtim.tv_nsec == mtime_.tv_nsec) {
    return {};
  }
  cv::Mat loaded = cv::imread(path_, cv::IMREAD_UNCHANGED);
  if (loaded.empty()) {
    // A half-written file reads as garbage: keep the previous image and try
    // again on the next frame.
    if (!image_.empty()) return {};
    return makeError(SourceErrc::kUnavailable, "file:" + path_ + ": not a readable image");
  }
  image_ = toEightBit(loaded);
  inode_ = st.st_ino;
  size_ = st.st_size;
  mtime_ = st.st_mtim;
  return {};
}

Result<SourceFrame> FileSource::grab(std::chrono::milliseconds /*timeout*/) {
  if (auto r = refresh(); !r) return r.error();
  SourceFrame frame;
  frame.image = image_;  // shared, read-only: the pipeline copies or converts it
  frame.layout = image_.channels() == 3 ? PixelLayout::kBGR8 : PixelLayout::kMono8;
  return frame;
}

}  // namespace picksight::video
