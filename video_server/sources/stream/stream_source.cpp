// Stream camera source.
#include "stream_source.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "picksight/codecs/codecs.hpp"
#include "picksight/common/clock.hpp"
#include "picksight/common/text.hpp"

namespace picksight::video {
namespace {
// FFmpeg's own timeouts, so that neither connecting to a dead host nor
// reading from a silent one blocks for ever.
constexpr int kOpenTimeoutMs = 5000;
constexpr int kReadTimeoutMs = 5000;
constexpr long long kMaxLatencyMs = 10000;
// Frames over which the least-delayed one is found: a few seconds of video,
// so that a lasting change of the network's delay is followed.
constexpr size_t kDelayWindow = 100;
constexpr size_t kMinClockSamples = 10;
// How far the presentation clock may run from the arrival clock over the
// window and still be taken for the sender's clock.
constexpr double kClockTolerance = 0.1;
}  // namespace

Result<StreamOptions> parseStreamOptions(const std::string& text) {
  // '|' never appears unescaped in a URL, so it cannot be part of one.
  const size_t bar = text.rfind('|');
  StreamOptions options;
  options.url = text.substr(0, bar);
  if (options.url.empty())
    return makeError(SourceErrc::kBadConfig, "stream: needs a URL, as in stream:rtsp://host/path");
  if (bar == std::string::npos) return options;
  const std::string option = text.substr(bar + 1);
  const std::string key = "latency_ms=";
  if (option.rfind(key, 0) != 0) {
    return makeError(SourceErrc::kBadConfig,
                     "stream: unknown option '" + option + "' after '|' (known: latency_ms=N)");
  }
  const auto value = parseInt(option.substr(key.size()));
  if (!value || *value < 0 || *value > kMaxLatencyMs) {
    return makeError(SourceErrc::kBadConfig,
                     "stream: latency_ms must be an integer in [0, 10000], got '" +
                         option.substr(key.size()) + "'");
  }
  options.latency = std::chrono::milliseconds(*value);
  return options;
}

std::chrono::nanoseconds StreamDelay::add(uint64_t in_ns, uint64_t decoded_ns, double pts_ms) {
  const std::chrono::nanoseconds decode(decoded_ns > in_ns ? decoded_ns - in_ns : 0);
  // No clock, or one that went back (a reconnection, a new stream): start again.
  if (!(pts_ms >= 0) || (!window_.empty() && pts_ms <= window_.back().pts_ms)) window_.clear();
  if (!(pts_ms >= 0)) return decode;
  window_.push_back({in_ns, pts_ms});
  if (window_.size() > kDelayWindow) window_.pop_front();
  if (!ptsIsAClock()) return decode;
  // A frame's offset (arrival minus presentation time) is its delay plus a
  // constant; the least-delayed frame of the window stands for no buffering.
  double least_ms = std::numeric_limits<double>::infinity();
  for (const Sample& sample : window_) {
    least_ms = std::min(least_ms, static_cast<double>(sample.in_ns) / 1e6 - sample.pts_ms);
  }
  const double lag_ms = static_cast<double>(in_ns) / 1e6 - pts_ms - least_ms;
  return decode + std::chrono::nanoseconds(static_cast<int64_t>(std::max(0.0, lag_ms) * 1e6));
}

bool StreamDelay::ptsIsAClock() const {
  if (window_.size() < kMinClockSamples) return false;
  const double arrived_ms = static_cast<double>(window_.back().in_ns - window_.front().in_ns) / 1e6;
  const double presented_ms = window_.back().pts_ms - window_.front().pts_ms;
  return arrived_ms > 0 && std::abs(presented_ms - arrived_ms) <= kClockTolerance * arrived_ms;
}

StreamSource::StreamSource(StreamOptions options)
    : url_(std::move(options.url)),
      latency_(options.latency),
      is_file_(url_.find("://") == std::string::npos) {}

StreamSource::~StreamSource() { close(); }

Result<void> StreamSource::open() {
  close();
  std::unique_ptr<codecs::VideoStream> capture;
  const std::vector<int> params = {cv::CAP_PROP_OPEN_TIMEOUT_MSEC, kOpenTimeoutMs,
                                   cv::CAP_PROP_READ_TIMEOUT_MSEC, kReadTimeoutMs};
  try {
    capture = codecs::newVideoStream();
    capture->open(url_, cv::CAP_FFMPEG, params);
  } catch (const std::exception& e) {
    // cv::Exception, or the codecs module missing from the installation.
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
    latest_delay_ = std::chrono::nanoseconds(0);
  }
  delay_.reset();
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
  codecs::VideoStream& capture = *capture_;
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
    uint64_t in_ns = 0;
    uint64_t decoded_ns = 0;
    double pts_ms = -1;
    try {
      // Read in two steps to time them: grab() returns once the frame's
      // bytes are in, retrieve() decodes them.
      ok = capture.grab();
      in_ns = monotonicNs();
      if (ok) pts_ms = capture.get(cv::CAP_PROP_POS_MSEC);
      ok = ok && capture.retrieve(frame) && !frame.empty();
      decoded_ns = monotonicNs();
    } catch (const cv::Exception&) {
      ok = false;  // a decoder error inside FFmpeg: the stream is unusable
    }
    const std::chrono::nanoseconds delay = ok && !is_file_
                                               ? delay_.add(in_ns, decoded_ns, pts_ms) + latency_
                                               : std::chrono::nanoseconds(0);
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
    latest_decoded_ns_ = decoded_ns;
    latest_delay_ = delay;
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
    // What a stream carries (MJPEG, H.264, H.265, a video file's codec) is
    // compressed with loss, colour at half resolution.
    frame.compressed = true;
    if (!is_file_) {
      // Its wait here, then its way from the sender to decoded.
      const uint64_t now = monotonicNs();
      frame.age =
          std::chrono::nanoseconds(now > latest_decoded_ns_ ? now - latest_decoded_ns_ : 0) +
          latest_delay_;
    }
    return frame;
  }
  if (ended_) return makeError(SourceErrc::kUnavailable, "stream:" + url_ + ": " + end_reason_);
  return makeError(SourceErrc::kTimeout, "stream:" + url_ + ": no frame within " +
                                             std::to_string(timeout.count()) + " ms");
}

std::vector<Feature> StreamSource::features() {
  std::vector<Feature> out;
  for (const char* name : {"latency_ms", "pipeline_delay_ms"}) out.push_back(*feature(name));
  return out;
}

Result<Feature> StreamSource::feature(const std::string& name) {
  Feature f;
  f.name = name;
  f.type = FeatureType::kFloat;
  f.unit = "ms";
  f.writable = false;
  if (name == "latency_ms") {
    f.value = std::to_string(latency_.count());
    f.description = "configured delay from exposure to arrival (source option |latency_ms=N)";
    return f;
  }
  if (name == "pipeline_delay_ms") {
    std::lock_guard<std::mutex> lock(mutex_);
    f.value = formatFixed(std::chrono::duration<double, std::milli>(latest_delay_).count(), 1);
    f.description =
        "the last frame's estimated delay from exposure to decoded: decode time, "
        "buffering measured against the stream's clock, and latency_ms";
    return f;
  }
  return makeError(SourceErrc::kUnknownFeature, "unknown feature '" + name + "'");
}

}  // namespace picksight::video
