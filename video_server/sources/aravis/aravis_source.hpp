// The Aravis camera: GigE Vision and USB3 Vision devices (and Aravis's fake
// GigE camera) as a streaming Source, with every GenICam feature by name.
//
// Threading: like every Source, called from its Camera's acquisition thread
// only. Aravis receives frames on its own stream thread, which only fills
// buffers from our pool and queues them; our one callback there asks for
// real-time scheduling when the thread starts and sets an atomic. The
// heartbeat thread's "control-lost" signal only sets an atomic flag.
//
// Buffers: a pool of kBufferCount buffers of the camera's payload size. grab()
// pops one and returns a SourceFrame whose image borrows its bytes, without a
// copy; the buffer goes back to the stream at the start of the next grab() (by
// then the Camera has converted or copied the frame), or when the stream is
// stopped. So the frame is valid exactly as long as the Source interface
// promises: until the next grab().
#pragma once

#include <arv.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "glib_ptr.hpp"
#include "picksight/sources/source.hpp"

namespace picksight::video {

class AravisSource : public Source {
 public:
  // `device_id` as Aravis names devices ("Aravis-Fake-GV01", a MAC or IP
  // address, a USB3 Vision GUID) or the camera's serial number ("GV01", as
  // printed on its label; looked up in the device list); empty = the first
  // device found.
  explicit AravisSource(std::string device_id);
  ~AravisSource() override;
  AravisSource(const AravisSource&) = delete;
  AravisSource& operator=(const AravisSource&) = delete;

  Result<void> open() override;
  void close() override;
  SourceInfo info() const override { return info_; }
  Result<SourceFrame> grab(std::chrono::milliseconds timeout) override;

  bool streams() const override { return true; }
  Result<void> configureAcquisition(const AcquisitionRequest& request) override;
  Result<void> softwareTrigger() override;
  bool hardwareTrigger() const override { return true; }
  DriverCounters driverCounters() const override;

  std::vector<Feature> features() override;
  std::vector<std::string> featureNames() override;
  std::optional<Feature> listedFeature(const std::string& name) override;
  Result<Feature> feature(const std::string& name) override;
  Result<void> setFeature(const std::string& name, const std::string& value) override;

 private:
  using Clock = std::chrono::steady_clock;

  // Creates the stream and its buffer pool for the current payload size.
  Result<void> createStream();
  Result<void> startAcquisition();
  // Writes the trigger mode and frame rate `request` asks for, and no more.
  std::optional<Error> configureTriggerAndRate(const AcquisitionRequest& request);
  // TriggerSelector FrameStart, TriggerSource, TriggerActivation (if given),
  // TriggerMode On; the error names the feature the camera refused.
  std::optional<Error> configureHardwareTrigger(const TriggerInput& input);
  void stopAcquisition();
  // Free-run: swaps `buffer` for the newest complete one queued behind it,
  // giving the older back to the stream.
  void takeNewest(GObjectPtr<ArvBuffer>& buffer);
  // Drops the stream, its counters added to retired_.
  void retireStream();
  // Gives the buffer the last frame borrowed back to the stream.
  void returnHeldBuffer();
  // grab()'s two halves: the next buffer within `timeout` (the device
  // checked when none comes), and the frame that borrows a complete one
  // (any other goes back to the stream).
  Result<GObjectPtr<ArvBuffer>> nextBuffer(std::chrono::milliseconds timeout);
  Result<SourceFrame> frameFrom(GObjectPtr<ArvBuffer> buffer);
  // A real control read: fails when the device is gone.
  Result<void> checkDevice();
  Error lost(const std::string& why) const;
  std::string label() const { return "aravis:" + device_id_; }

  const std::string device_id_;
  GObjectPtr<ArvCamera> camera_;
  GObjectPtr<ArvStream> stream_;
  GObjectPtr<ArvBuffer> held_;  // popped buffer the last SourceFrame borrows
  size_t buffer_size_ = 0;
  DriverCounters retired_;      // counters of the streams dropped so far
  uint64_t skipped_stale_ = 0;  // frames passed over for a newer one
  // Set on the stream thread: 1 real-time scheduling granted, -1 refused.
  std::atomic<int> stream_priority_{0};
  bool socket_buffer_warned_ = false;  // the rmem_max warning is written once
  bool priority_logged_ = false;       // and the stream thread's priority once
  bool acquiring_ = false;
  std::optional<AcquisitionMode> mode_;  // as last configured
  // Why the last configureAcquisition failed: grab() answers with it rather
  // than streaming in a mode nobody asked for.
  std::optional<Error> configure_error_;
  SourceInfo info_;

  // Set from Aravis's heartbeat thread when the device stops answering. Shared
  // with the signal handler, which may outlive a disconnect by one emission.
  std::shared_ptr<std::atomic<bool>> control_lost_;
  gulong control_lost_handler_ = 0;

  // Liveness: a free-running camera that sends nothing for a while is asked
  // a control read; one that does not answer is gone.
  Clock::time_point last_alive_;
  // Software triggers whose frame has not arrived yet, and when the last one
  // was sent: a trigger repeated while its frame is in flight is not sent
  // twice (the Camera asks again after a grab slice times out).
  int triggers_in_flight_ = 0;
  Clock::time_point last_trigger_;
};

}  // namespace picksight::video
