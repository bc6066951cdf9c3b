// Directory camera source.
#include "dir_source.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>
#include "picksight/codecs/codecs.hpp"

#include "eight_bit_image.hpp"
#include "picksight/common/frame.hpp"
#include "picksight/common/log.hpp"

namespace picksight::video {
namespace fs = std::filesystem;
namespace {

// imread's depths and channel counts to a layout the pipeline standardizes:
// 16-bit grey stays Mono16 (scaled there), the rest becomes 8-bit mono or BGR.
SourceFrame toFrame(cv::Mat image) {
  SourceFrame frame;
  if (image.type() == CV_16UC1) {
    frame.image = std::move(image);
    frame.layout = PixelLayout::kMono16;
    return frame;
  }
  image = toEightBit(image);
  frame.layout = image.channels() == 3 ? PixelLayout::kBGR8 : PixelLayout::kMono8;
  frame.image = std::move(image);
  return frame;
}

}  // namespace

DirSource::DirSource(std::string path) : path_(std::move(path)) {}

Result<void> DirSource::open() {
  listed_ = false;
  last_name_.clear();
  if (auto r = refreshListing(); !r) return r;
  // The first readable image gives the sensor size the camera checks ROIs against.
  auto first = grab(std::chrono::milliseconds(0));
  if (!first) return first.error();
  first_size_ = first->image.size();
  last_name_.clear();  // serve that image again as the first frame
  return {};
}

void DirSource::close() {
  names_.clear();
  listed_ = false;
  last_name_.clear();
}

SourceInfo DirSource::info() const {
  SourceInfo i;
  i.vendor = "PickSight";
  i.model = "dir";
  i.serial = path_;
  i.sensor_width = first_size_.width;
  i.sensor_height = first_size_.height;
  i.formats = {"Mono8", "Mono16", "BGR8"};
  return i;
}

Result<void> DirSource::refreshListing() {
  struct stat st {};
  if (::stat(path_.c_str(), &st) != 0) {
    return makeError(SourceErrc::kUnavailable, "dir:" + path_ + ": " + std::strerror(errno));
  }
  if (!S_ISDIR(st.st_mode))
    return makeError(SourceErrc::kUnavailable, "dir:" + path_ + ": not a directory");
  // Adding, removing or renaming an entry changes the directory's mtime;
  // rewriting a file in place does not, but every grab reads its file afresh.
  if (listed_ && !racy_ && st.st_mtim.tv_sec == listed_mtime_.tv_sec &&
      st.st_mtim.tv_nsec == listed_mtime_.tv_nsec) {
    return {};
  }
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(path_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    // Hidden files are the temporaries of writers that rename into place.
    if (name.empty() || name[0] == '.') continue;
    std::error_code type_ec;
    if (!it->is_regular_file(type_ec)) continue;
    names.push_back(name);
  }
  if (ec) return makeError(SourceErrc::kUnavailable, "dir:" + path_ + ": " + ec.message());
  // Plain byte order: recordings use zero-padded numbers, which sort right.
  std::sort(names.begin(), names.end());
  names_ = std::move(names);
  listed_mtime_ = st.st_mtim;
  listed_ = true;
  // Directory mtimes move in kernel ticks: a change within the tick of this
  // listing would leave the mtime as it is now. Until the mtime is older
  // than any tick, list again on every grab (as git does with racy entries).
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  const double age =
      double(now.tv_sec - st.st_mtim.tv_sec) + 1e-9 * double(now.tv_nsec - st.st_mtim.tv_nsec);
  racy_ = age < 0.1;
  return {};
}

Result<SourceFrame> DirSource::grab(std::chrono::milliseconds /*timeout*/) {
  if (auto r = refreshListing(); !r) return r.error();
  if (names_.empty()) return makeError(SourceErrc::kUnavailable, "dir:" + path_ + ": no files");
  // Start after the last name served, wrapping: at most one pass over the
  // listing, so a directory of unreadable files is an error, not a hang.
  const size_t start = static_cast<size_t>(
      std::upper_bound(names_.begin(), names_.end(), last_name_) - names_.begin());
  for (size_t k = 0; k < names_.size(); ++k) {
    const std::string& name = names_[(start + k) % names_.size()];
    const std::string file = path_ + "/" + name;
    cv::Mat image;
    try {
      image = picksight::codecs::imread(file, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
      image.release();  // a decoder that throws on a corrupt file: skipped like any unreadable one
    }
    last_name_ = name;
    if (image.empty()) {
      if (warned_.insert(name).second)
        logWarning("dir:", path_, ": skipping ", name, ": not a readable image");
      continue;
    }
    warned_.erase(name);  // rewritten into a good image: warn again if it breaks again
    SourceFrame frame = toFrame(std::move(image));
    frame.compressed = isJpegFile(file);
    return frame;
  }
  return makeError(SourceErrc::kUnavailable, "dir:" + path_ + ": no readable image among " +
                                                 std::to_string(names_.size()) + " files");
}

}  // namespace picksight::video
