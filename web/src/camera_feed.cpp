// The camera feed's subscriber thread and its shared, lazy JPEG encoder.
#include "picksight/web/camera_feed.hpp"

#include <time.h>

#include <algorithm>

#include "picksight/common/log.hpp"
#include "picksight/transport/frame_message.hpp"
#include "picksight/web/idle_priority.hpp"

namespace picksight::web {

using transport::FrameSubscriber;

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
      encoder_(jpeg_quality),
      starved_encoder_(jpeg_quality) {
  thread_ = std::thread([this, &context] { run(context); });
  encode_thread_ = std::thread([this] { encodeLoop(); });
}

CameraFeed::~CameraFeed() {
  stop();
  if (thread_.joinable()) thread_.join();
  if (encode_thread_.joinable()) encode_thread_.join();
}

void CameraFeed::stop() {
  stop_ = true;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    changed_.notify_all();
  }
  std::lock_guard<std::mutex> lock(encode_mutex_);
  encode_stopping_ = true;
  encode_wake_.notify_all();
  encoded_.notify_all();
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

std::shared_ptr<const EncodedJpeg> CameraFeed::jpeg(uint64_t generation,
                                                    std::chrono::milliseconds timeout) {
  if (generation == 0) generation = this->generation();
  if (generation == 0) return nullptr;  // no frame yet
  std::unique_lock<std::mutex> lock(encode_mutex_);
  if (jpeg_ && jpeg_->generation >= generation) return jpeg_;
  if (wanted_ < generation) {
    wanted_ = generation;
    encode_wake_.notify_one();
  }
  const auto done = [&] { return attempted_ >= generation || encode_stopping_; };
  if (!encoded_.wait_for(lock, std::min(timeout, kEncoderStarved), done) &&
      timeout > kEncoderStarved) {
    // The cores have been busy all along: encode at this thread's priority.
    lock.unlock();
    {
      std::lock_guard<std::mutex> starved(starved_mutex_);
      bool needed = false;
      {
        std::lock_guard<std::mutex> check(encode_mutex_);
        needed = !done();  // another starved caller may have done it meanwhile
      }
      if (needed) encodeNewest(starved_encoder_);
    }
    lock.lock();
  }
  return jpeg_ && jpeg_->generation >= generation ? jpeg_ : nullptr;
}

void CameraFeed::encodeLoop() {
  runAtIdlePriority("camera " + camera_ + ": JPEG encoder");
  std::unique_lock<std::mutex> lock(encode_mutex_);
  while (true) {
    encode_wake_.wait(lock, [&] { return wanted_ > attempted_ || encode_stopping_; });
    if (encode_stopping_) return;
    lock.unlock();
    encodeNewest(encoder_);
    lock.lock();
  }
}

void CameraFeed::encodeNewest(JpegEncoder& encoder) {
  std::shared_ptr<const Frame> frame;
  uint64_t generation = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    frame = latest_;
    generation = generation_;
  }
  if (!frame) return;
  const uint64_t start = threadCpuNs();
  auto bytes = encoder.encode(frame->image);
  encode_ns_ += threadCpuNs() - start;
  std::shared_ptr<EncodedJpeg> jpeg;
  if (bytes) {
    ++encoded_frames_;
    jpeg = std::make_shared<EncodedJpeg>();
    jpeg->generation = generation;
    jpeg->sequence = frame->info.sequence;
    jpeg->host_timestamp_ns = frame->info.host_timestamp_ns;
    jpeg->bytes = std::move(*bytes);
  } else {
    logWarning("camera ", camera_, ": ", bytes.error().message);
  }
  std::lock_guard<std::mutex> lock(encode_mutex_);
  // The encoder thread and a starved caller may both have encoded: the
  // newest JPEG stays.
  if (jpeg && (!jpeg_ || jpeg_->generation < generation)) jpeg_ = std::move(jpeg);
  attempted_ = std::max(attempted_, generation);
  encoded_.notify_all();
}

double CameraFeed::encodeSeconds() const { return static_cast<double>(encode_ns_.load()) * 1e-9; }

}  // namespace picksight::web
