// The camera feed's subscriber thread and its shared, lazy JPEG.
#include "picksight/web/camera_feed.hpp"

#include <time.h>

#include "picksight/common/log.hpp"
#include "picksight/transport/frame_message.hpp"

namespace picksight::web {
namespace {

uint64_t threadCpuNs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<uint64_t>(ts.tv_nsec);
}

}  // namespace

CameraFeed::CameraFeed(zmq::context_t& context, std::string frames_endpoint, std::string camera,
                       int jpeg_quality)
    : frames_endpoint_(std::move(frames_endpoint)),
      camera_(std::move(camera)),
      encoder_(jpeg_quality) {
  thread_ = std::thread([this, &context] { run(context); });
}

CameraFeed::~CameraFeed() {
  stop();
  if (thread_.joinable()) thread_.join();
}

void CameraFeed::stop() {
  stop_ = true;
  std::lock_guard<std::mutex> lock(mutex_);
  stopping_ = true;
  changed_.notify_all();
}

void CameraFeed::run(zmq::context_t& context) {
  try {
    // A short queue: the web shows the newest frame, older ones are useless.
    FrameSubscriber subscriber(context, frames_endpoint_, camera_, 2);
    while (!stop_) {
      auto frame = subscriber.receive(std::chrono::milliseconds(200));
      if (!frame) continue;
      auto shared = std::make_shared<const Frame>(std::move(*frame));
      std::lock_guard<std::mutex> lock(mutex_);
      latest_ = std::move(shared);
      ++generation_;
      changed_.notify_all();
    }
  } catch (const std::exception& e) {
    // Never leaves the thread: the camera just shows no new frames.
    logError("camera ", camera_, ": frame feed stopped: ", e.what());
  }
}

std::shared_ptr<const Frame> CameraFeed::latest() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

uint64_t CameraFeed::generation() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return generation_;
}

uint64_t CameraFeed::waitNewer(uint64_t seen, std::chrono::milliseconds timeout) const {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait_for(lock, timeout, [&] { return generation_ != seen || stopping_; });
  return generation_;
}

std::shared_ptr<const EncodedJpeg> CameraFeed::jpeg() {
  auto frame = latest();
  if (!frame) return nullptr;
  std::lock_guard<std::mutex> lock(encode_mutex_);
  if (jpeg_of_ == frame.get()) return jpeg_;
  const uint64_t start = threadCpuNs();
  auto bytes = encoder_.encode(frame->image);
  encode_ns_ += threadCpuNs() - start;
  if (!bytes) {
    logWarning("camera ", camera_, ": ", bytes.error().message);
    return nullptr;
  }
  ++encoded_frames_;
  auto jpeg = std::make_shared<EncodedJpeg>();
  jpeg->sequence = frame->info.sequence;
  jpeg->host_timestamp_ns = frame->info.host_timestamp_ns;
  jpeg->bytes = std::move(*bytes);
  jpeg_ = std::move(jpeg);
  jpeg_of_ = frame.get();
  jpeg_frame_ = std::move(frame);
  return jpeg_;
}

double CameraFeed::encodeSeconds() const { return static_cast<double>(encode_ns_.load()) * 1e-9; }

}  // namespace picksight::web
