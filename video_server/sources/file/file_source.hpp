// The file camera: one image served on every frame or trigger, re-read when
// the file changes so tests and offline work can swap scenes by renaming a
// new file over it. A file that is gone, empty or unreadable is covered by
// the last image for `grace` (counted from the first grab that found it so),
// then every grab fails with SourceErrc::kUnavailable: the camera reports
// itself as failing (state "reconnecting", last_error) until the file is
// readable again, instead of serving an old scene as if it were new.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <ctime>
#include <optional>
#include <string>

#include "picksight/sources/source.hpp"

namespace picksight::video {

class FileSource : public Source {
 public:
  static constexpr std::chrono::milliseconds kDefaultGrace{1000};

  explicit FileSource(std::string path, std::chrono::milliseconds grace = kDefaultGrace);

  Result<void> open() override;
  void close() override;
  SourceInfo info() const override;
  Result<SourceFrame> grab(std::chrono::milliseconds timeout) override;

 private:
  // Re-reads the file if its identity or content stamp changed.
  Result<void> refresh();
  // The file cannot be read (`why`): fine while the grace lasts, an error after.
  Result<void> failing(const std::string& why);

  std::string path_;
  std::chrono::milliseconds grace_;
  // When a grab first found the file unreadable; unset while it reads.
  std::optional<std::chrono::steady_clock::time_point> failing_since_;
  cv::Mat image_;      // last good image, CV_8UC1 or CV_8UC3
  bool jpeg_ = false;  // image_ came from a JPEG (SourceFrame::compressed)
  // What the file was when image_ was read: a rename over it changes the
  // inode, an in-place rewrite the size or mtime.
  ino_t inode_ = 0;
  off_t size_ = -1;
  timespec mtime_{};
};

}  // namespace picksight::video
