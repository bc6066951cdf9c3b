// File camera source.
#include "file_source.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include "picksight/codecs/codecs.hpp"

#include "eight_bit_image.hpp"
#include "picksight/common/frame.hpp"

namespace picksight::video {

FileSource::FileSource(std::string path, std::chrono::milliseconds grace)
    : path_(std::move(path)), grace_(grace) {}

Result<void> FileSource::open() { return refresh(); }

void FileSource::close() {
  image_.release();
  failing_since_.reset();
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
  if (::stat(path_.c_str(), &st) != 0) return failing(std::strerror(errno));
  if (!image_.empty() && st.st_ino == inode_ && st.st_size == size_ &&
      st.st_mtim.tv_sec == mtime_.tv_sec && st.st_mtim.tv_nsec == mtime_.tv_nsec) {
    failing_since_.reset();  // back as it was (moved away and back)
    return {};
  }
  cv::Mat loaded = picksight::codecs::imread(path_, cv::IMREAD_UNCHANGED);
  if (loaded.empty()) return failing("not a readable image");
  failing_since_.reset();
  image_ = toEightBit(loaded);
  // Its first bytes read again: a file renamed over the path in between
  // has another inode than `st`'s, and is read whole at the next grab.
  jpeg_ = isJpegFile(path_);
  inode_ = st.st_ino;
  size_ = st.st_size;
  mtime_ = st.st_mtim;
  return {};
}

Result<void> FileSource::failing(const std::string& why) {
  const auto now = std::chrono::steady_clock::now();
  if (!failing_since_) failing_since_ = now;
  // A file being replaced (rewritten in place, or deleted then created) is
  // briefly gone or half-written: the last image stands in for it a moment.
  if (!image_.empty() && now - *failing_since_ <= grace_) return {};
  std::string message = "file:" + path_ + ": " + why;
  if (!image_.empty()) {
    message += " for more than " + std::to_string(grace_.count()) + " ms";
  }
  return makeError(SourceErrc::kUnavailable, message);
}

Result<SourceFrame> FileSource::grab(std::chrono::milliseconds /*timeout*/) {
  if (auto r = refresh(); !r) return r.error();
  SourceFrame frame;
  frame.image = image_;  // shared, read-only: the pipeline copies or converts it
  frame.layout = image_.channels() == 3 ? PixelLayout::kBGR8 : PixelLayout::kMono8;
  frame.compressed = jpeg_;
  return frame;
}

}  // namespace picksight::video
