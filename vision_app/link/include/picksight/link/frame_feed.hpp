// The vision app's view of one camera: a thread that receives its frames and
// keeps the newest, decoded, so a request can wait for a frame taken after it.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <zmq.hpp>

#include "picksight/transport/frame_message.hpp"

namespace picksight::link {

class FrameFeed {
 public:
  // With `curve` keys, frames come sealed and their key is asked at
  // `control_endpoint` (see transport::FrameSubscriber).
  FrameFeed(zmq::context_t& context, std::string endpoint, std::string camera,
            std::optional<transport::CurveClientKeys> curve = std::nullopt,
            std::string control_endpoint = {});
  ~FrameFeed();

  void start();
  void stop();

  // The newest frame with a sequence number of at least `sequence` that was
  // received after `after_ns` (CLOCK_MONOTONIC), waiting for it up to
  // `timeout`; nullptr on timeout. The receive time guards against a video
  // server that restarted and counts sequences from 1 again.
  std::shared_ptr<const Frame> waitFor(uint64_t sequence, uint64_t after_ns,
                                       std::chrono::milliseconds timeout);
  std::shared_ptr<const Frame> latest() const;
  uint64_t framesReceived() const { return received_.load(); }

 private:
  void run();

  zmq::context_t& context_;
  const std::string endpoint_;
  const std::string camera_;
  const std::optional<transport::CurveClientKeys> curve_;
  const std::string control_endpoint_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> received_{0};

  mutable std::mutex mutex_;  // guards latest_
  std::condition_variable arrived_;
  std::shared_ptr<const Frame> latest_;
};

}  // namespace picksight::link
