// The directory camera: an image sequence served in name order, one image per
// frame or trigger, looping, for replaying recorded production.
#pragma once

#include <ctime>
#include <set>
#include <string>
#include <vector>

#include "picksight/sources/source.hpp"

namespace picksight::video {

// Threading: like every source, called from its camera's acquisition thread only.
class DirSource : public Source {
 public:
  explicit DirSource(std::string path);

  Result<void> open() override;
  void close() override;
  SourceInfo info() const override;
  // The next readable image after the last one served; files that do not
  // decode are skipped with a warning (once per file).
  Result<SourceFrame> grab(std::chrono::milliseconds timeout) override;

 private:
  // Re-lists the directory when its modification time changed: files added,
  // removed or renamed into it.
  Result<void> refreshListing();

  std::string path_;
  std::vector<std::string> names_;  // regular, non-hidden files, sorted by name
  timespec listed_mtime_{};
  bool listed_ = false;
  bool racy_ = false;  // listed within a timestamp tick of the last change
  // The last name served: after a re-listing the sequence goes on from the
  // first name after it, whatever was inserted or removed.
  std::string last_name_;
  std::set<std::string> warned_;  // unreadable files already reported
  cv::Size first_size_;
};

}  // namespace picksight::video
