// Frame feed thread: owns the SUB socket for its whole life.
#include "picksight/link/frame_feed.hpp"

#include "picksight/common/log.hpp"

namespace picksight::link {

using transport::CurveClientKeys;
using transport::FrameSubscriber;

FrameFeed::FrameFeed(zmq::context_t& context, std::string endpoint, std::string camera,
                     std::optional<CurveClientKeys> curve, std::string control_endpoint)
    : context_(context),
      endpoint_(std::move(endpoint)),
      camera_(std::move(camera)),
      curve_(std::move(curve)),
      control_endpoint_(std::move(control_endpoint)) {}

FrameFeed::~FrameFeed() { stop(); }

void FrameFeed::start() {
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread([this] { run(); });
}

void FrameFeed::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void FrameFeed::run() {
  try {
    // Only the newest frame matters to a locator: a short queue keeps latency
    // low when processing is slower than the camera.
    FrameSubscriber subscriber(context_, endpoint_, camera_, 2, curve_, control_endpoint_);
    while (!stop_) {
      auto frame = subscriber.receive(std::chrono::milliseconds(100));
      if (!frame) continue;
      auto shared = std::make_shared<const Frame>(std::move(*frame));
      {
        std::lock_guard<std::mutex> lock(mutex_);
        latest_ = std::move(shared);
      }
      ++received_;
      arrived_.notify_all();
    }
  } catch (const std::exception& e) {
    logError("frame feed ", endpoint_, ": ", e.what());
  }
}

std::shared_ptr<const Frame> FrameFeed::latest() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

std::shared_ptr<const Frame> FrameFeed::waitFor(uint64_t sequence, uint64_t after_ns,
                                                std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto fresh = [&] {
    return latest_ && latest_->info.sequence >= sequence && latest_->info.received_ns >= after_ns;
  };
  arrived_.wait_for(lock, timeout, fresh);
  return fresh() ? latest_ : nullptr;
}

}  // namespace picksight::link
