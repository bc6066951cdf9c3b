// Frame publisher thread: queues frames from the cameras, sends them with the codec.
#include "picksight/video_server/frame_publisher.hpp"

#include <zmq.h>

#include <atomic>
#include <cstring>

#include "picksight/common/log.hpp"

namespace picksight::video {

using transport::FrameKey;
using transport::FrameSealer;
using transport::sendFrame;

namespace {
std::atomic<int> g_monitor_id{0};
}  // namespace

FramePublisher::FramePublisher(zmq::context_t& context, const std::string& endpoint,
                               size_t queue_limit, int subscriber_queue,
                               std::optional<FrameKey> seal)
    : socket_(context, zmq::socket_type::pub),
      monitor_(context, zmq::socket_type::pair),
      queue_limit_(queue_limit),
      sealer_(seal ? std::make_unique<FrameSealer>(*seal) : nullptr) {
  socket_.set(zmq::sockopt::sndhwm, subscriber_queue * 3);  // HWM counts parts
  socket_.set(zmq::sockopt::linger, 0);
  const std::string monitor_endpoint =
      "inproc://picksight-publisher-monitor-" + std::to_string(g_monitor_id++);
  if (zmq_socket_monitor(socket_.handle(), monitor_endpoint.c_str(),
                         ZMQ_EVENT_ACCEPTED | ZMQ_EVENT_DISCONNECTED) != 0) {
    throw zmq::error_t();
  }
  monitor_.connect(monitor_endpoint);
  socket_.bind(endpoint);
  bound_endpoint_ = socket_.get(zmq::sockopt::last_endpoint);
}

FramePublisher::~FramePublisher() { stop(); }

void FramePublisher::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread([this] { run(); });
}

void FramePublisher::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void FramePublisher::publish(Frame frame) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() >= queue_limit_) {
      ++counters_[queue_.front().info.camera].dropped;
      queue_.pop_front();
    }
    queue_.push_back(std::move(frame));
  }
  wake_.notify_one();
}

PublisherCounters FramePublisher::counters(const std::string& camera) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = counters_.find(camera);
  return it == counters_.end() ? PublisherCounters{} : it->second;
}

void FramePublisher::pollMonitor() {
  for (;;) {
    zmq::message_t event;
    if (!monitor_.recv(event, zmq::recv_flags::dontwait)) return;
    uint16_t id = 0;
    if (event.size() >= sizeof(id)) std::memcpy(&id, event.data(), sizeof(id));
    zmq::message_t address;
    if (event.more()) (void)monitor_.recv(address);
    if (id == ZMQ_EVENT_ACCEPTED) ++subscribers_;
    if (id == ZMQ_EVENT_DISCONNECTED && subscribers_ > 0) --subscribers_;
  }
}

void FramePublisher::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    wake_.wait_for(lock, std::chrono::milliseconds(100),
                   [this] { return stop_ || !queue_.empty(); });
    while (!queue_.empty() && !stop_) {
      Frame frame = std::move(queue_.front());
      queue_.pop_front();
      lock.unlock();
      try {
        if (sealer_) {
          sealer_->send(socket_, frame);
        } else {
          sendFrame(socket_, frame);
        }
      } catch (const zmq::error_t& e) {
        logError("publisher: send failed: ", e.what());
      }
      lock.lock();
      ++counters_[frame.info.camera].published;
    }
    lock.unlock();
    pollMonitor();
    lock.lock();
  }
  lock.unlock();
  zmq_socket_monitor(socket_.handle(), nullptr, 0);
  socket_.close();
  monitor_.close();
}

}  // namespace picksight::video
