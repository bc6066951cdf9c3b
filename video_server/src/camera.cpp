// Camera acquisition loop: open with back-off, pace or wait for triggers,
// grab, apply output settings, hand over.
//
// The synthetic and file sources render or read on demand, so this thread is
// their acquisition thread. Drivers with their own delivery thread (Aravis)
// only hand buffers to grab(); the conversion work happens here, never on
// the driver's thread.
#include "picksight/video_server/camera.hpp"

#include <algorithm>

#include "picksight/common/clock.hpp"
#include "picksight/common/log.hpp"

namespace picksight::video {
namespace {
constexpr std::chrono::milliseconds kMaxBackoff{5000};
constexpr std::chrono::milliseconds kGrabTimeout{1000};
}  // namespace

Camera::Camera(CameraConfig config, std::unique_ptr<Source> source, FrameSink& sink)
    : config_(std::move(config)),
      source_(std::move(source)),
      sink_(sink),
      output_(config_.output),
      mode_(config_.mode),
      fps_(config_.fps) {
  status_.name = config_.name;
  status_.uri = config_.uri;
  status_.state = "stopped";
}

Camera::~Camera() { stop(); }

void Camera::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (thread_.joinable()) return;
  stop_ = false;
  status_.state = "opening";
  thread_ = std::thread([this] { run(); });
}

void Camera::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::lock_guard<std::mutex> lock(mutex_);
  if (open_) source_->close();
  open_ = false;
  status_.state = "stopped";
}

CameraStatus Camera::status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  CameraStatus s = status_;
  s.mode = mode_;
  s.fps_setting = fps_;
  s.output = output_;
  return s;
}

Result<void> Camera::setOutput(const OutputSettings& output) {
  std::lock_guard<std::mutex> lock(mutex_);
  const cv::Size sensor(status_.info.sensor_width, status_.info.sensor_height);
  if (auto ok = validateOutputSettings(output, sensor); !ok) return ok;
  output_ = output;
  return {};
}

OutputSettings Camera::output() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return output_;
}

Result<void> Camera::setMode(AcquisitionMode mode, double fps) {
  if (fps < 0 || fps > 1000) return makeError(1, "fps must be in (0, 1000]");
  {
    std::lock_guard<std::mutex> lock(mutex_);
    mode_ = mode;
    if (fps > 0) fps_ = fps;
    if (mode == AcquisitionMode::kFreeRun) pending_triggers_ = 0;
  }
  wake_.notify_all();
  return {};
}

TriggerTicket Camera::trigger() {
  TriggerTicket ticket;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (mode_ == AcquisitionMode::kTrigger) {
      ticket.sequence = next_sequence_ + pending_triggers_;
      ticket.triggered = true;
      ++pending_triggers_;
    } else {
      // Sequence numbers are taken when a grab starts, so next_sequence_ is
      // a frame whose acquisition begins after this request.
      ticket.sequence = next_sequence_;
    }
  }
  wake_.notify_all();
  return ticket;
}

void Camera::waitBackoff(std::unique_lock<std::mutex>& lock) {
  wake_.wait_for(lock, backoff_, [this] { return stop_; });
  backoff_ = std::min(backoff_ * 2, kMaxBackoff);
}

bool Camera::ensureOpen(std::unique_lock<std::mutex>& lock) {
  if (open_) return true;
  lock.unlock();
  Result<void> opened = source_->open();
  SourceInfo info;
  if (opened) info = source_->info();
  lock.lock();
  if (!opened) {
    status_.state = "reconnecting";
    if (status_.last_error != opened.error().message) {
      logWarning("camera ", config_.name, ": ", opened.error().message, " (retrying)");
    }
    status_.last_error = opened.error().message;
    waitBackoff(lock);
    return false;
  }
  if (ever_opened_) {
    ++status_.reconnects;
    logInfo("camera ", config_.name, ": reconnected");
  }
  ever_opened_ = true;
  open_ = true;
  backoff_ = std::chrono::milliseconds(100);
  status_.info = info;
  status_.state = "streaming";
  status_.last_error.clear();
  return true;
}

void Camera::run() {
  using Clock = std::chrono::steady_clock;
  auto next_due = Clock::now();
  uint64_t last_frame_ns = 0;
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    if (!ensureOpen(lock)) continue;

    // Wait for the next frame's turn: a trigger, or the free-run period.
    bool triggered = false;
    if (mode_ == AcquisitionMode::kTrigger) {
      wake_.wait(lock, [this] {
        return stop_ || pending_triggers_ > 0 || mode_ != AcquisitionMode::kTrigger;
      });
      if (stop_ || mode_ != AcquisitionMode::kTrigger) continue;
      triggered = true;
      --pending_triggers_;
    } else {
      const auto period = std::chrono::duration_cast<Clock::duration>(
          std::chrono::duration<double>(1.0 / std::max(fps_, 1e-3)));
      const AcquisitionMode mode = mode_;
      const double fps = fps_;
      wake_.wait_until(lock, next_due,
                       [&] { return stop_ || mode_ != mode || fps_ != fps; });
      if (stop_ || mode_ != mode) continue;
      if (fps_ != fps) {
        next_due = Clock::now();
        continue;
      }
      // Behind by more than a period (a slow grab): restart the cadence
      // rather than bursting to catch up.
      next_due = std::max(next_due + period, Clock::now());
    }
    const uint64_t sequence = next_sequence_++;
    const OutputSettings output = output_;
    lock.unlock();

    Result<SourceFrame> grabbed = source_->grab(kGrabTimeout);
    const uint64_t host_ns = realtimeNs();

    if (!grabbed) {
      lock.lock();
      ++status_.acquisition_errors;
      status_.last_error = grabbed.error().message;
      if (triggered) ++pending_triggers_;  // the trigger is still owed a frame
      if (grabbed.error().code != kSourceTimeout) {
        logWarning("camera ", config_.name, ": ", grabbed.error().message);
        lock.unlock();
        source_->close();
        lock.lock();
        open_ = false;
        status_.state = "reconnecting";
        waitBackoff(lock);
      }
      continue;
    }

    PublishedFrame frame;
    frame.camera = config_.name;
    frame.sequence = sequence;
    frame.device_timestamp_ns = grabbed->device_timestamp_ns;
    frame.host_timestamp_ns = host_ns;
    frame.triggered = triggered;
    frame.output = applyOutputSettings(grabbed->image, output);
    frame.truth = std::move(grabbed->truth);
    sink_.publish(std::move(frame));

    lock.lock();
    ++status_.frames_acquired;
    status_.last_sequence = sequence;
    if (last_frame_ns != 0) {
      // Exponential average of the instantaneous rate: smooth, and follows a
      // rate change within a few frames.
      const double rate = 1e9 / static_cast<double>(std::max<uint64_t>(1, host_ns - last_frame_ns));
      status_.fps_measured =
          status_.fps_measured == 0 ? rate : 0.9 * status_.fps_measured + 0.1 * rate;
    }
    last_frame_ns = host_ns;
  }
}

}  // namespace picksight::video
