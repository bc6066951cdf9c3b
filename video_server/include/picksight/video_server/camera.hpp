// A camera of the video server: owns one source and its acquisition thread,
// applies the output settings, and hands finished frames to a FrameSink.
//
// Threading: the acquisition thread is the only caller of the source. All
// public methods are safe from any thread (the control thread calls them).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "picksight/common/frame.hpp"
#include "picksight/sources/source.hpp"
#include "picksight/video_server/frame_pipeline.hpp"

namespace picksight::video {

// The highest frame rate a camera may be set to.
constexpr double kMaxFps = 1000;

// Hardware trigger settings: the camera's input, and how long a client that
// asked for a frame waits for a pulse (the camera itself waits for ever: no
// pulse is not silence, and the no-frame timeout does not apply).
struct HardwareTrigger {
  TriggerInput input;
  std::chrono::milliseconds timeout{10000};
};
constexpr std::chrono::milliseconds kMaxTriggerTimeout{3600000};
// GenICam's standard TriggerActivation values, the ones accepted.
constexpr const char* kTriggerActivations = "RisingEdge, FallingEdge, AnyEdge, LevelHigh, LevelLow";
bool isTriggerActivation(const std::string& name);

struct CameraConfig {
  std::string name;
  std::string uri;
  OutputSettings output;
  AcquisitionMode mode = AcquisitionMode::kFreeRun;
  double fps = 10;
  // Whether the configuration gave the mode or the rate: a streaming device
  // keeps its own trigger and frame-rate settings unless asked (a request
  // from a client asks too).
  bool mode_asked = false;
  bool fps_asked = false;
  // Feature values applied, in order, every time the device is (re)opened:
  // a camera that was power-cycled has forgotten them.
  std::vector<std::pair<std::string, std::string>> features;
  // No good frame for this long while frames are expected (free-run, or a
  // trigger owed one): the camera reports it and reopens the source.
  std::chrono::milliseconds no_frame_timeout{5000};
  HardwareTrigger hardware;
};

// Where a camera's frames go: Frames whose image the camera made for them
// alone (continuous, owned). publish() must not block: the acquisition thread
// calls it and a slow consumer must never slow the camera.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual void publish(Frame frame) = 0;
};

struct TriggerTicket {
  uint64_t sequence = 0;   // the frame to wait for (or any later one)
  bool triggered = false;  // false in free-run: no frame was forced
  // The mode the ticket was taken in, and in kHardwareTrigger the settings a
  // client needs to wait for the pulse (taken together, under one lock).
  AcquisitionMode mode = AcquisitionMode::kFreeRun;
  HardwareTrigger hardware;
};

struct CameraStatus {
  std::string name;
  std::string uri;
  // "opening", "streaming", "reconnecting", "closed" (stream closed on
  // request, device released), "stopped" (thread not running)
  std::string state;
  // Why it fails; a camera reopened for delivering no good frame keeps it
  // until a good frame comes.
  std::string last_error;
  bool open_requested = true;
  AcquisitionMode mode = AcquisitionMode::kFreeRun;
  HardwareTrigger hardware;
  double fps_setting = 0;
  double fps_measured = 0;
  SourceInfo info;
  OutputSettings output;
  uint64_t frames_acquired = 0;
  // Failed grabs: bad frames, outages, no frame for no_frame_timeout.
  uint64_t acquisition_errors = 0;
  uint64_t reconnects = 0;
  uint64_t last_sequence = 0;
  // Frames of a source that reports their age (streams) left out because
  // they were exposed before the request they would have served.
  uint64_t frames_before_request = 0;
  DriverCounters driver;  // as of the last grab
};

class Camera {
 public:
  Camera(CameraConfig config, std::unique_ptr<Source> source, FrameSink& sink);
  ~Camera();
  Camera(const Camera&) = delete;
  Camera& operator=(const Camera&) = delete;

  void start();
  void stop();

  const std::string& name() const { return config_.name; }
  CameraStatus status() const;

  // Output settings take effect from the next frame; validated against the
  // sensor size once the source has been opened.
  Result<void> setOutput(const OutputSettings& output);
  OutputSettings output() const;
  // fps 0 leaves the rate. `hardware` replaces the hardware trigger settings
  // (kHardwareTrigger); a source without a trigger input refuses that mode
  // with kNotSupported.
  Result<void> setMode(AcquisitionMode mode, double fps,
                       const std::optional<HardwareTrigger>& hardware = std::nullopt);

  // In trigger mode queues one frame and returns its sequence number. In
  // free-run returns the first sequence number acquired after this call; in
  // hardware trigger mode, that of the first frame delivered after it (the
  // next pulse's, unless one was in flight). With a source that reports its
  // frames' age (a stream), the frame that carries the number was exposed
  // after this call by estimate (older ones are left out and their number
  // reused), and concurrent requests get numbers of their own.
  // A closed camera (kCameraClosed) or one in an outage (SourceErrc::
  // kUnavailable, state "reconnecting") refuses at once; triggers still owed
  // when an outage starts are dropped, never served in a burst afterwards.
  Result<TriggerTicket> trigger();

  // Opens or closes the stream. A closed camera releases its device (another
  // program may use it) and keeps its settings.
  void setOpen(bool open);

  // The last published frame with a sequence of at least `sequence`, waiting
  // up to `timeout` for it; nullopt on timeout.
  std::optional<Frame> waitForFrame(uint64_t sequence, std::chrono::milliseconds timeout);

  // Feature access runs on the acquisition thread, between grabs, so the
  // source is only ever called from one thread. The list is read in slices
  // of at most half a frame period (10 to 100 ms) with a grab between them:
  // listing hundreds of features does not stop the frames.
  Result<std::vector<Feature>> features();
  Result<Feature> feature(const std::string& name);
  Result<Feature> setFeature(const std::string& name, const std::string& value);

  // The simulated robot of a synthetic source. moveTarget runs on the
  // acquisition thread: frames acquired after it returns show the target
  // there. simulatedRobot() answers from the last known state, without
  // waiting for the acquisition thread. Other sources: kNotSupported.
  Result<SimulatedRobot> moveTarget(std::optional<cv::Point2d> at_mm);
  Result<SimulatedRobot> simulatedRobot() const;

 private:
  using Command = std::function<void()>;
  using Clock = std::chrono::steady_clock;

  // One grab, standardized and with the output settings applied.
  struct Grab {
    Result<SourceFrame> grabbed = Error{};
    Result<OutputFrame> out = Error{};
    uint64_t host_ns = 0;     // CLOCK_REALTIME when grabbed
    uint64_t exposed_ns = 0;  // CLOCK_MONOTONIC of the exposure (estimated: host_ns - age)
    std::chrono::nanoseconds age{0};
    DriverCounters counters;  // the source's, right after the grab
  };

  // The acquisition loop and its steps; the steps called with `lock` return
  // with it held.
  void run();
  void waitWhileClosed(std::unique_lock<std::mutex>& lock);
  void applyAcquisitionSettings(std::unique_lock<std::mutex>& lock);
  // Waits for the next frame's turn: whether it was triggered, or nullopt
  // when woken for something else (stop, a command, a setting).
  std::optional<bool> waitForTurn(std::unique_lock<std::mutex>& lock, bool streams);
  // Called without the lock.
  Grab grabAndConvert(bool triggered, bool streams, const OutputSettings& output);
  void handleGrabFailure(std::unique_lock<std::mutex>& lock, uint64_t sequence, bool triggered,
                         const Error& error);
  void publish(std::unique_lock<std::mutex>& lock, uint64_t sequence, bool triggered, Grab grab);
  // A frame exposed before a request it would serve (sources that report
  // their frames' age): left out, its number and its trigger given back.
  bool exposedTooEarly(uint64_t sequence, const Grab& grab) const;
  void leaveOut(uint64_t sequence, bool triggered);
  bool ensureOpen(std::unique_lock<std::mutex>& lock);
  void closeSource(std::unique_lock<std::mutex>& lock);
  void waitBackoff(std::unique_lock<std::mutex>& lock);
  // Closes the source and waits before reopening it: an outage.
  void startOutage(std::unique_lock<std::mutex>& lock);
  // A frame that could not be used: counted, logged at a bounded rate.
  void logBadFrame(const Error& error);
  // Runs the queued commands. `all`: also those queued while they run
  // (when stopping); else only those queued before, so that a command whose
  // caller queues the next one when answered (a feature listing's slices)
  // lets a grab come between the two, whoever gets the CPU first.
  void runCommands(std::unique_lock<std::mutex>& lock, bool all);
  // How long one slice of a feature listing may hold the acquisition thread.
  std::chrono::milliseconds featureSlice() const;
  // Runs `fn` on the acquisition thread and waits for it.
  template <typename T>
  Result<T> onAcquisitionThread(std::function<Result<T>(Source&, bool open)> fn);

  const CameraConfig config_;
  const std::unique_ptr<Source> source_;  // acquisition thread only
  const bool source_reports_age_;         // a constant of the driver
  FrameSink& sink_;
  std::thread thread_;
  // When the pending software trigger was sent (acquisition thread only).
  std::optional<Clock::time_point> trigger_sent_;
  Clock::time_point next_due_;  // of the next free-run frame (acquisition thread only)
  uint64_t last_frame_ns_ = 0;  // host time of the last frame (acquisition thread only)
  // Since when a frame is expected and none good came (acquisition thread only).
  std::optional<Clock::time_point> waiting_since_;
  // Bad frames since the last warning about them, and when it was written
  // (acquisition thread only).
  uint64_t bad_frames_unlogged_ = 0;
  std::optional<Clock::time_point> bad_frame_logged_;

  mutable std::mutex mutex_;  // guards everything below
  std::condition_variable wake_;
  std::condition_variable frame_published_;
  bool stop_ = false;
  bool open_ = false;
  bool open_requested_ = true;
  bool reconfigure_ = true;  // acquisition settings changed since the source last heard
  std::deque<Command> commands_;
  std::optional<Frame> last_frame_;
  cv::Size frame_size_;  // of the frames the device delivers (sensor pixels)
  bool ever_opened_ = false;
  // No good frame since a reopening for silence: reported until one comes.
  bool stalled_ = false;
  std::chrono::milliseconds backoff_{100};
  OutputSettings output_;
  AcquisitionMode mode_;
  HardwareTrigger hardware_;
  double fps_;
  bool mode_asked_;
  bool fps_asked_;
  uint64_t next_sequence_ = 1;
  std::optional<uint64_t> grab_sequence_;  // the number of the grab under way, if one is
  bool grab_waits_pulse_ = false;          // that grab was begun in hardware trigger mode
  uint64_t pending_triggers_ = 0;
  // Requests waiting for a frame of a source that reports its frames' age:
  // (ticket sequence, CLOCK_MONOTONIC of the request), sequences ascending.
  std::deque<std::pair<uint64_t, uint64_t>> requests_;
  CameraStatus status_;
  std::optional<SimulatedRobot> robot_;  // the source's simulated robot, if it has one
};

}  // namespace picksight::video
