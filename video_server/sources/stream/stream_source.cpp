// Stream camera source.
#include "stream_source.hpp"

#include <opencv2/videoio.hpp>
#include <utility>
#include <vector>

namespace picksight::video {
namespace {
// FFmpeg's own timeouts, so that neither connecting to a dead host nor
// reading from a silent one blocks for ever.
constexpr int kOpenTimeoutMs = 5000;
constexpr int kReadTimeoutMs = 5000;
}  // namespace

StreamSource::StreamSource(std::string url)
    : url_(std::move(url)), is_file_(url_.find("://") == std::string::npos) {}

StreamSource::~StreamSource() { close(); }

Result<void> StreamSource::open() {
  close();
  auto capture = std::make_unique<cv::VideoCapture>();
  const std::vector<int> params = {cv::CAP_PROP_OPEN_TIMEOUT_MSEC, kOpenTimeoutMs,
                                   cv::CAP_PROP_READ_TIMEOUT_MSEC, kReadTimeoutMs};
  try {
    capture->open(url_, cv::CAP_FFMPEG, params);
  } catch (const cv::Exception& e) {
    return makeError(SourceErrc::kUnavailable, "stream:" + url_ + ": " + e.what());
  }
  if (!capture->isOpened())
    return makeError(SourceErrc::kUnavailable, "stream:" + url_ + ": cannot open");
  width_ = static_cast<int>(capture->get(cv::CAP_PROP_FRAME_WIDTH));
  height_ = static_cast<int>(capture->get(cv::CAP_PROP_FRAME_HEIGHT));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = false;
    ended_ = false;
    end_reason_.clear();
    has_frame_ = false;
    latest_.release();
  }
  capture_ = std::move(capture);
  reader_ = std::thread([this] { readLoop(); });
  return {};
}

void StreamSource::close() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  frame_taken_.notify_all();
  if (reader_.joinable()) reader_.join();
  capture_.reset();
}

SourceInfo StreamSource::info() const {
  SourceInfo i;
  i.vendor = "FFmpeg";
  i.model = "stream";
  i.serial = url_;
  i.sensor_width = width_;
  i.sensor_height = height_;
  i.formats = {"BGR8"};
  return i;
}

void StreamSource::readLoop() {
  cv::VideoCapture& capture = *capture_;
  bool rewound = false;  // a file that fails right after a rewind is broken, not at its end
  for (;;) {
    {
      // A file is read at the consumer's pace, one frame ahead: every frame
      // is served, and nothing is decoded only to be overwritten.
      std::unique_lock<std::mutex> lock(mutex_);
      frame_taken_.wait(lock, [this] { return stop_ || !is_file_ || !has_frame_; });
      if (stop_) return;
    }
    cv::Mat frame;
    bool ok = false;
    try {
      ok = capture.read(frame) && !frame.empty();
    } catch (const cv::Exception&) {
      ok = false;  // a decoder error inside FFmpeg: the stream is unusable
    }
    if (!ok && is_file_ && !rewound) {
      rewound = true;
      try {
        capture.set(cv::CAP_PROP_POS_FRAMES, 0);
      } catch (const cv::Exception&) {
      }
      continue;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (!ok) {
      ended_ = true;
      end_reason_ = is_file_ ? "cannot read" : "stream ended or lost";
      frame_ready_.notify_all();
      return;
    }
    rewound = false;
    latest_ = std::move(frame);  // the newest wins: a slow consumer skips frames
    has_frame_ = true;
    frame_ready_.notify_all();
  }
}

Result<SourceFrame> StreamSource::grab(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (!reader_.joinable())
    return makeError(SourceErrc::kUnavailable, "stream:" + url_ + ": not open");
  frame_ready_.wait_for(lock, timeout, [this] { return has_frame_ || ended_; });
  if (has_frame_) {
    SourceFrame frame;
    frame.image = std::move(latest_);
    latest_ = cv::Mat();
    has_frame_ = false;
    frame_taken_.notify_all();
    frame.layout = frame.image.channels() == 1 ? PixelLayout::kMono8 : PixelLayout::kBGR8;
    return frame;
  }
  if (ended_) return makeError(SourceErrc::kUnavailable, "stream:" + url_ + ": " + end_reason_);
  return makeError(SourceErrc::kTimeout, "stream:" + url_ + ": no frame within " +
                                             std::to_string(timeout.count()) + " ms");
}

}  // namespace picksight::video
