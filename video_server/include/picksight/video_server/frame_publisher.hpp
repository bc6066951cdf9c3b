// Publishes camera frames on a ZeroMQ PUB socket, one topic per camera, as
// 3-part messages (the frame codec's sendFrame: topic, FrameHeader, pixels
// sent without copying).
//
// Threading: the PUB socket belongs to the publisher thread. publish() may be
// called from any camera thread; it only queues. Slow subscribers lose frames
// in their own ZeroMQ pipe (bounded by the send high-water mark); they never
// slow the cameras or the other subscribers.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <zmq.hpp>

#include "picksight/transport/frame_message.hpp"
#include "picksight/transport/frame_seal.hpp"
#include "picksight/video_server/camera.hpp"

namespace picksight::video {

struct PublisherCounters {
  uint64_t published = 0;
  uint64_t dropped = 0;  // dropped before sending: the publisher fell behind
};

class FramePublisher : public FrameSink {
 public:
  // Binds at once so a bad endpoint fails at start-up. `queue_limit` frames
  // wait at most; `subscriber_queue` frames per subscriber in ZeroMQ. With
  // `seal` every frame is sealed once with that key (frame_seal.hpp), on
  // the publisher's thread, for all subscribers: the socket stays plain.
  FramePublisher(zmq::context_t& context, const std::string& endpoint, size_t queue_limit = 8,
                 int subscriber_queue = 4, std::optional<transport::FrameKey> seal = {});
  ~FramePublisher() override;

  // The endpoint actually bound (a wildcard port resolved).
  const std::string& boundEndpoint() const { return bound_endpoint_; }

  void start();
  void stop();
  void publish(Frame frame) override;

  PublisherCounters counters(const std::string& camera) const;
  int subscribers() const { return subscribers_.load(); }

 private:
  void run();
  void pollMonitor();

  zmq::socket_t socket_;   // publisher thread only (after start)
  zmq::socket_t monitor_;  // publisher thread only (after start)
  std::string bound_endpoint_;
  const size_t queue_limit_;
  const std::unique_ptr<transport::FrameSealer> sealer_;  // with a key
  std::thread thread_;
  std::atomic<int> subscribers_{0};

  mutable std::mutex mutex_;  // guards the fields below
  std::condition_variable wake_;
  std::deque<Frame> queue_;
  std::map<std::string, PublisherCounters> counters_;
  bool stop_ = false;
};

}  // namespace picksight::video
