// The file camera: one image served on every frame or trigger, re-read when
// the file changes so tests and offline work can swap scenes by renaming a
// new file over it.
#pragma once

#include <sys/types.h>

#include <ctime>
#include <string>

#include "picksight/sources/source.hpp"

namespace picksight::video {

class FileSource : public Source {
 public:
  explicit FileSource(std::string path);

  Result<void> open() override;
  void close() override;
  SourceInfo info() const override;
  Result<SourceFrame> grab(std::chrono::milliseconds timeout) override;

 private:
  // Re-reads the file if its identity or content stamp changed.
  Result<void> refresh();

  std::string path_;
  cv::Mat image_;  // last good image, CV_8UC1 or CV_8UC3
  // What the file was when image_ was read: a rename over it changes the
  // inode, an in-place rewrite the size or mtime.
  ino_t inode_ = 0;
  off_t size_ = -1;
  timespec mtime_{};
};

}  // namespace picksight::video
