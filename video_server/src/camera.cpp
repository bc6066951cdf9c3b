// Camera acquisition loop: open with back-off, pace or wait for triggers,
// grab, standardize and apply output settings, hand over.
//
// The synthetic and file sources render or read on demand, so this thread is
// their acquisition thread. Streaming drivers (Aravis, V4L2) receive buffers
// on their own thread or in the kernel and only hand them to grab(); the
// conversion work happens here, never on the driver's thread.
#include "picksight/video_server/camera.hpp"

#include "picksight/video_server/video_errors.hpp"

#include <algorithm>
#include <set>

#include "picksight/common/clock.hpp"
#include "picksight/common/log.hpp"
#include "picksight/common/text.hpp"
#include "picksight/video_server/pixel_format.hpp"

namespace picksight::video {
namespace {
constexpr std::chrono::milliseconds kMaxBackoff{5000};
// Streaming sources are polled in short slices so feature commands and stop
// requests are served promptly even when no frame comes.
constexpr std::chrono::milliseconds kGrabSlice{200};
constexpr std::chrono::milliseconds kTriggerPatience{2000};
// Bad frames come at the frame rate: one warning per this interval at most.
constexpr std::chrono::seconds kBadFrameLogInterval{10};
// Requests remembered for a late source; beyond, the oldest are forgotten
// (their clients have long timed out).
constexpr size_t kMaxRequests = 256;
}  // namespace

bool isTriggerActivation(const std::string& name) {
  static const std::set<std::string> kNames = {"RisingEdge", "FallingEdge", "AnyEdge", "LevelHigh",
                                               "LevelLow"};
  return kNames.count(name) > 0;
}

Camera::Camera(CameraConfig config, std::unique_ptr<Source> source, FrameSink& sink)
    : config_(std::move(config)),
      source_(std::move(source)),
      source_reports_age_(source_->reportsAge()),
      sink_(sink),
      output_(config_.output),
      mode_(config_.mode),
      hardware_(config_.hardware),
      fps_(config_.fps),
      mode_asked_(config_.mode_asked),
      fps_asked_(config_.fps_asked) {
  status_.name = config_.name;
  status_.uri = config_.uri;
  status_.state = "stopped";
  // No thread runs yet: the source may be asked here. Afterwards only
  // moveTarget() changes the robot, and it refreshes robot_.
  if (auto robot = source_->simulatedRobot()) robot_ = *robot;
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
  std::unique_lock<std::mutex> lock(mutex_);
  closeSource(lock);
  // Commands queued after the thread ended still get an answer.
  runCommands(lock, true);
  status_.state = "stopped";
}

CameraStatus Camera::status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  CameraStatus s = status_;
  s.mode = mode_;
  s.hardware = hardware_;
  s.fps_setting = fps_;
  s.output = output_;
  s.open_requested = open_requested_;
  return s;
}

Result<void> Camera::setOutput(const OutputSettings& output) {
  std::lock_guard<std::mutex> lock(mutex_);
  // The frames the device actually delivers bound the ROI: a camera whose
  // own Width/Height feature is below its sensor size sends smaller images.
  const cv::Size sensor = !frame_size_.empty()
                              ? frame_size_
                              : cv::Size(status_.info.sensor_width, status_.info.sensor_height);
  if (auto ok = validateOutputSettings(output, sensor); !ok) return ok;
  output_ = output;
  return {};
}

OutputSettings Camera::output() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return output_;
}

Result<void> Camera::setMode(AcquisitionMode mode, double fps,
                             const std::optional<HardwareTrigger>& hardware) {
  // Written so that NaN fails too.
  if (!(fps >= 0 && fps <= kMaxFps))
    return makeError(VideoErrc::kOutOfRange, "fps must be in (0, 1000]");
  // A constant of the driver: asking it here does not race the acquisition thread.
  if (mode == AcquisitionMode::kHardwareTrigger && !source_->hardwareTrigger()) {
    return makeError(SourceErrc::kNotSupported, "camera '" + config_.name + "' (" + config_.uri +
                                                    ") has no hardware trigger input");
  }
  if (hardware && (hardware->input.line.empty() || hardware->timeout.count() <= 0 ||
                   hardware->timeout > kMaxTriggerTimeout)) {
    return makeError(VideoErrc::kOutOfRange,
                     "hardware trigger: a line and a timeout in (0, 3600000] ms are needed");
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (hardware) hardware_ = *hardware;
    mode_ = mode;
    mode_asked_ = true;
    if (fps > 0) {
      fps_ = fps;
      fps_asked_ = true;
    }
    if (mode != AcquisitionMode::kTrigger) pending_triggers_ = 0;
    requests_.clear();
    reconfigure_ = true;
  }
  wake_.notify_all();
  return {};
}

void Camera::setOpen(bool open) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    open_requested_ = open;
    if (!open) {
      pending_triggers_ = 0;
      requests_.clear();
    }
  }
  wake_.notify_all();
}

Result<TriggerTicket> Camera::trigger() {
  TriggerTicket ticket;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!open_requested_) {
      return makeError(VideoErrc::kCameraClosed, "camera '" + config_.name + "' is closed");
    }
    // During an outage the answer is an error at once: a queued trigger
    // would be served, with every other one, in a burst when the camera
    // returns, long after anybody waited for it.
    if (status_.state == "reconnecting") {
      return makeError(SourceErrc::kUnavailable,
                       "camera '" + config_.name + "' is not streaming: " + status_.last_error);
    }
    ticket.mode = mode_;
    ticket.hardware = hardware_;
    if (mode_ == AcquisitionMode::kTrigger) {
      ticket.sequence = next_sequence_ + pending_triggers_;
      ticket.triggered = true;
      ++pending_triggers_;
    } else if (mode_ == AcquisitionMode::kHardwareTrigger && grab_sequence_ && grab_waits_pulse_ &&
               !reconfigure_) {
      // The grab under way waits for the next pulse: the first frame
      // delivered after this request carries its number. (A grab begun
      // before the switch to this mode may bring a free-run frame: the next
      // one is the first that waits for a pulse.)
      ticket.sequence = *grab_sequence_;
    } else {
      // Sequence numbers are taken when a grab starts, so next_sequence_ is
      // a frame whose acquisition begins after this request.
      ticket.sequence = next_sequence_;
    }
    if (source_reports_age_) {
      // One frame per request: each frame is held to the request it serves,
      // and a later request never raises the bar for an earlier one.
      if (!requests_.empty())
        ticket.sequence = std::max(ticket.sequence, requests_.back().first + 1);
      requests_.emplace_back(ticket.sequence, monotonicNs());
      if (requests_.size() > kMaxRequests) requests_.pop_front();
    }
  }
  wake_.notify_all();
  return ticket;
}

std::optional<Frame> Camera::waitForFrame(uint64_t sequence, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto ready = [&] { return last_frame_ && last_frame_->info.sequence >= sequence; };
  frame_published_.wait_for(lock, timeout, ready);
  if (!ready()) return std::nullopt;
  return last_frame_;
}

void Camera::runCommands(std::unique_lock<std::mutex>& lock, bool all) {
  for (size_t queued = commands_.size(); !commands_.empty() && (all || queued-- > 0);) {
    Command command = std::move(commands_.front());
    commands_.pop_front();
    lock.unlock();
    command();
    lock.lock();
  }
}

void Camera::waitBackoff(std::unique_lock<std::mutex>& lock) {
  wake_.wait_for(lock, backoff_,
                 [this] { return stop_ || !commands_.empty() || !open_requested_; });
  backoff_ = std::min(backoff_ * 2, kMaxBackoff);
}

void Camera::closeSource(std::unique_lock<std::mutex>& lock) {
  if (!open_) return;
  open_ = false;
  lock.unlock();
  source_->close();
  lock.lock();
}

bool Camera::ensureOpen(std::unique_lock<std::mutex>& lock) {
  if (open_) return true;
  lock.unlock();
  Result<void> opened = source_->open();
  SourceInfo info;
  if (opened) {
    for (const auto& [name, value] : config_.features) {
      if (auto set = source_->setFeature(name, value); !set) {
        logWarning("camera ", config_.name, ": feature ", name, " = ", value, ": ",
                   set.error().message);
      }
    }
    info = source_->info();
  }
  lock.lock();
  if (!opened) {
    status_.state = "reconnecting";
    pending_triggers_ = 0;  // their clients get no frame; new ones are refused
    requests_.clear();
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
  reconfigure_ = true;
  waiting_since_.reset();
  status_.info = info;
  status_.state = "streaming";
  // A camera reopened because it delivered nothing says so until it does:
  // opening is not streaming.
  if (!stalled_) {
    status_.last_error.clear();
    backoff_ = std::chrono::milliseconds(100);
  }
  return true;
}

void Camera::run() {
  next_due_ = Clock::now();
  last_frame_ns_ = 0;
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    runCommands(lock, false);
    if (!open_requested_) {
      waitWhileClosed(lock);
      continue;
    }
    if (!ensureOpen(lock)) continue;
    if (reconfigure_) applyAcquisitionSettings(lock);
    const bool streams = source_->streams();
    const std::optional<bool> triggered = waitForTurn(lock, streams);
    if (!triggered) continue;  // woken for something else

    const uint64_t sequence = next_sequence_++;
    const OutputSettings output = output_;
    if (!waiting_since_) waiting_since_ = Clock::now();
    grab_sequence_ = sequence;
    grab_waits_pulse_ = mode_ == AcquisitionMode::kHardwareTrigger;
    const cv::Size known_size = frame_size_;
    lock.unlock();
    Grab grab = grabAndConvert(*triggered, streams, output);
    // The device's frames changed size (a file: camera's image replaced by
    // one of another size): what it says of itself is asked again, on this
    // thread as at open, so that the sensor size everybody maps ROIs and
    // parts through follows without a restart.
    std::optional<SourceInfo> resized;
    if (grab.out && !known_size.empty() && grab.out->sensor_size != known_size)
      resized = source_->info();
    lock.lock();
    if (resized) {
      logInfo("camera ", config_.name, ": frames of ", grab.out->sensor_size.width, "x",
              grab.out->sensor_size.height, " now (were ", known_size.width, "x", known_size.height,
              "); sensor ", resized->sensor_width, "x", resized->sensor_height);
      status_.info = *resized;
    }
    grab_sequence_.reset();
    status_.driver = grab.counters;
    if (!grab.out) {
      handleGrabFailure(lock, sequence, *triggered, grab.out.error());
      continue;
    }
    if (exposedTooEarly(sequence, grab)) {
      leaveOut(sequence, *triggered);
      continue;
    }
    publish(lock, sequence, *triggered, std::move(grab));
  }
}

void Camera::waitWhileClosed(std::unique_lock<std::mutex>& lock) {
  closeSource(lock);
  status_.state = "closed";
  wake_.wait(lock, [this] { return stop_ || open_requested_ || !commands_.empty(); });
}

void Camera::applyAcquisitionSettings(std::unique_lock<std::mutex>& lock) {
  reconfigure_ = false;
  waiting_since_.reset();  // the wait for a frame starts again
  const AcquisitionRequest request{mode_, fps_, mode_asked_, fps_asked_, hardware_.input};
  lock.unlock();
  const Result<void> configured = source_->configureAcquisition(request);
  lock.lock();
  if (!configured) {
    status_.last_error = configured.error().message;
    logWarning("camera ", config_.name, ": ", configured.error().message);
  }
  next_due_ = Clock::now();
}

std::optional<bool> Camera::waitForTurn(std::unique_lock<std::mutex>& lock, bool streams) {
  // A trigger, or the free-run period (sources that stream pace themselves).
  if (mode_ == AcquisitionMode::kTrigger) {
    wake_.wait(lock, [this] {
      return stop_ || pending_triggers_ > 0 || mode_ != AcquisitionMode::kTrigger || reconfigure_ ||
             !open_requested_ || !commands_.empty();
    });
    if (stop_ || pending_triggers_ == 0 || mode_ != AcquisitionMode::kTrigger || reconfigure_ ||
        !open_requested_) {
      return std::nullopt;
    }
    --pending_triggers_;
    return true;
  }
  if (streams) return false;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / std::max(fps_, 1e-3)));
  wake_.wait_until(lock, next_due_, [&] {
    return stop_ || reconfigure_ || mode_ != AcquisitionMode::kFreeRun || !open_requested_ ||
           !commands_.empty();
  });
  if (Clock::now() < next_due_) return std::nullopt;
  // Behind by more than a period (a slow grab): restart the cadence rather
  // than bursting to catch up.
  next_due_ = std::max(next_due_ + period, Clock::now());
  return false;
}

Camera::Grab Camera::grabAndConvert(bool triggered, bool streams, const OutputSettings& output) {
  // A streaming camera may take longer than one grab slice to deliver a
  // triggered frame: trigger once, then keep waiting, and only trigger
  // again if the frame never came (a lost trigger packet).
  const auto now = Clock::now();
  const bool retrigger = !trigger_sent_ || now - *trigger_sent_ > kTriggerPatience;
  Result<void> asked;
  if (triggered && retrigger) {
    asked = source_->softwareTrigger();
    trigger_sent_ = now;
  }
  Grab grab;
  grab.grabbed = asked ? source_->grab(streams ? kGrabSlice : std::chrono::milliseconds(1000))
                       : Result<SourceFrame>(asked.error());
  grab.host_ns = realtimeNs();
  grab.exposed_ns = monotonicNs();
  if (grab.grabbed) {
    grab.age = std::max(std::chrono::nanoseconds(0), grab.grabbed->age);
    grab.exposed_ns -= std::min<uint64_t>(grab.exposed_ns, grab.age.count());
  }
  grab.counters = source_->driverCounters();
  // Standardize, then ROI and resize, in the pipeline's one step.
  grab.out = grab.grabbed ? applyOutputSettings(*grab.grabbed, output)
                          : Result<OutputFrame>(grab.grabbed.error());
  return grab;
}

void Camera::handleGrabFailure(std::unique_lock<std::mutex>& lock, uint64_t sequence,
                               bool triggered, const Error& error) {
  // The sequence number was not used: give it back so a gap means a lost frame.
  if (next_sequence_ == sequence + 1) next_sequence_ = sequence;
  if (triggered) ++pending_triggers_;  // the trigger is still owed a frame
  if (error.code == SourceErrc::kUnavailable) {
    ++status_.acquisition_errors;
    logWarning("camera ", config_.name, ": ", error.message);
    status_.last_error = error.message;
    startOutage(lock);
    return;
  }
  if (error.code == SourceErrc::kTimeout) {
    if (mode_ == AcquisitionMode::kHardwareTrigger) {
      // Waiting for a pulse on the line: nothing is owed, so no silence.
      // The source still checks that the device answers.
      waiting_since_.reset();
      return;
    }
    // A streaming camera with nothing to deliver yet: an error only once
    // it lasts (below), or when a trigger waits for it.
    if (triggered) ++status_.acquisition_errors;
  } else {
    // A bad frame (a corrupt buffer, settings too big for it): drop it and go on.
    ++status_.acquisition_errors;
    status_.last_error = error.message;
    logBadFrame(error);
  }
  if (!waiting_since_ || Clock::now() - *waiting_since_ < config_.no_frame_timeout) return;
  // Silence or only bad frames: a stream that never reaches us (firewall,
  // wrong interface, a camera left in trigger mode) or a hung device.
  // Reopening is the one remedy the server has.
  ++status_.acquisition_errors;
  std::string why =
      "no good frame for " +
      formatFixed(std::chrono::duration<double>(config_.no_frame_timeout).count(), 1) + " s";
  if (error.code != SourceErrc::kTimeout) why += " (last: " + error.message + ")";
  // Logged once per silence, however many reopenings it takes.
  if (!stalled_) logWarning("camera ", config_.name, ": ", why, "; reopening the device");
  stalled_ = true;
  status_.last_error = why;
  startOutage(lock);
}

bool Camera::exposedTooEarly(uint64_t sequence, const Grab& grab) const {
  if (!source_reports_age_) return false;
  // The latest request this frame would serve.
  uint64_t asked_ns = 0;
  for (const auto& [ticket, at_ns] : requests_) {
    if (ticket > sequence) break;
    asked_ns = std::max(asked_ns, at_ns);
  }
  return grab.exposed_ns < asked_ns;
}

void Camera::leaveOut(uint64_t sequence, bool triggered) {
  // As for a failed grab: no gap in the numbers, the trigger still owed.
  if (next_sequence_ == sequence + 1) next_sequence_ = sequence;
  if (triggered) ++pending_triggers_;
  ++status_.frames_before_request;
}

void Camera::startOutage(std::unique_lock<std::mutex>& lock) {
  closeSource(lock);
  status_.state = "reconnecting";
  waiting_since_.reset();
  requests_.clear();
  // Owed frames are not delivered after the outage; their clients time
  // out, and new triggers are refused until the camera is back.
  pending_triggers_ = 0;
  waitBackoff(lock);
}

void Camera::logBadFrame(const Error& error) {
  ++bad_frames_unlogged_;
  const auto now = Clock::now();
  if (bad_frame_logged_ && now - *bad_frame_logged_ < kBadFrameLogInterval) return;
  if (bad_frames_unlogged_ > 1) {
    logWarning("camera ", config_.name, ": ", bad_frames_unlogged_,
               " frames dropped in the last seconds, the last: ", error.message);
  } else {
    logWarning("camera ", config_.name, ": frame dropped: ", error.message);
  }
  bad_frames_unlogged_ = 0;
  bad_frame_logged_ = now;
}

void Camera::publish(std::unique_lock<std::mutex>& lock, uint64_t sequence, bool triggered,
                     Grab grab) {
  trigger_sent_.reset();
  waiting_since_.reset();
  if (stalled_) {
    stalled_ = false;
    status_.last_error.clear();
    logInfo("camera ", config_.name, ": frames again");
  }
  backoff_ = std::chrono::milliseconds(100);
  Frame frame;
  const OutputFrame& out = *grab.out;
  frame.image = out.image;
  frame.mapping = {static_cast<double>(out.roi_offset.x), static_cast<double>(out.roi_offset.y),
                   out.scale_x, out.scale_y};
  frame.info.camera = config_.name;
  frame.info.sequence = sequence;
  frame.info.device_timestamp_ns = grab.grabbed->device_timestamp_ns;
  // A late source's frame is stamped with its estimated exposure.
  frame.info.host_timestamp_ns =
      grab.host_ns - std::min<uint64_t>(grab.host_ns, static_cast<uint64_t>(grab.age.count()));
  frame.info.width = static_cast<uint32_t>(frame.image.cols);
  frame.info.height = static_cast<uint32_t>(frame.image.rows);
  frame.info.triggered = triggered;
  frame.info.compressed = grab.grabbed->compressed || grab.grabbed->layout == PixelLayout::kMJPEG;
  frame.truth = std::move(grab.grabbed->truth);
  // Statistics first, then the hand-over: a subscriber must never hold a
  // frame that `stats` does not count yet.
  // The standardized size is the size of the frames the device delivers.
  frame_size_ = out.sensor_size;
  last_frame_ = frame;
  ++status_.frames_acquired;
  status_.last_sequence = sequence;
  while (!requests_.empty() && requests_.front().first <= sequence) requests_.pop_front();
  if (last_frame_ns_ != 0) {
    // Exponential average of the instantaneous rate: smooth, and follows a
    // rate change within a few frames.
    const double rate =
        1e9 / static_cast<double>(std::max<uint64_t>(1, grab.host_ns - last_frame_ns_));
    status_.fps_measured =
        status_.fps_measured == 0 ? rate : 0.9 * status_.fps_measured + 0.1 * rate;
  }
  last_frame_ns_ = grab.host_ns;
  lock.unlock();
  sink_.publish(std::move(frame));
  lock.lock();
  frame_published_.notify_all();
}

}  // namespace picksight::video
