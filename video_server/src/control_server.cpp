// Control socket loop and its workers. A malformed request gets an error
// reply, so a REQ client is never left waiting while the server runs.
#include "picksight/video_server/control_server.hpp"

#include <algorithm>
#include <exception>
#include <sstream>
#include <utility>

#include "picksight/common/log.hpp"
#include "picksight/video_server/control_errors.hpp"
#include "picksight/video_server/control_request.hpp"
#include "picksight/video_server/video_errors.hpp"

namespace picksight::video {

using transport::kMaxControlRequestBytes;
using transport::secureServerSocket;

namespace {
constexpr std::chrono::milliseconds kPollPeriod{100};  // how soon the socket thread sees stop()

// Sends the envelope then `body`, all parts but the last with sndmore.
// Returns false when the message could not be queued at once.
bool sendRouted(zmq::socket_t& socket, std::vector<zmq::message_t>& envelope, zmq::message_t body) {
  for (auto& part : envelope) {
    if (!socket.send(part, zmq::send_flags::sndmore | zmq::send_flags::dontwait)) return false;
  }
  return socket.send(body, zmq::send_flags::dontwait).has_value();
}
}  // namespace

ControlServer::ControlServer(zmq::context_t& context, const std::string& endpoint, Handler handler,
                             ControlServerOptions options)
    : context_(context),
      handler_(std::move(handler)),
      options_(options),
      socket_(context, zmq::socket_type::router),
      replies_(context, zmq::socket_type::pull) {
  socket_.set(zmq::sockopt::linger, 0);
  // ZeroMQ drops a bigger message and closes the connection that sent it,
  // before it is buffered whole: the client gets no reply and times out.
  socket_.set(zmq::sockopt::maxmsgsize, static_cast<int64_t>(kMaxControlRequestBytes));
  secureServerSocket(socket_, options_.curve);
  socket_.bind(endpoint);
  bound_endpoint_ = socket_.get(zmq::sockopt::last_endpoint);
  // Unique within the context: several servers may share one.
  std::ostringstream name;
  name << "inproc://picksight-control-replies-" << static_cast<const void*>(this);
  replies_endpoint_ = name.str();
  replies_.set(zmq::sockopt::linger, 0);
  replies_.bind(replies_endpoint_);
}

ControlServer::~ControlServer() { stop(); }

void ControlServer::start() {
  if (socket_thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = false;
  }
  for (size_t i = 0; i < std::max<size_t>(1, options_.workers); ++i) {
    workers_.emplace_back([this] { runWorker(); });
  }
  socket_thread_ = std::thread([this] { runSocket(); });
}

void ControlServer::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    // Queued requests are dropped: their clients time out, as they would
    // with a server that went away.
    lanes_.clear();
    ready_.clear();
    pending_ = 0;
  }
  work_ready_.notify_all();
  if (socket_thread_.joinable()) socket_thread_.join();
  for (auto& w : workers_) {
    if (w.joinable()) w.join();
  }
  workers_.clear();
  std::lock_guard<std::mutex> lock(mutex_);
  lanes_.clear();  // a job a worker left behind while stopping
}

proto::ControlReply ControlServer::answer(const proto::ControlRequest& request) {
  try {
    return handler_(request);
  } catch (const std::exception& e) {
    logError("control: ", e.what());
    return errorReply(makeError(VideoErrc::kInternal, std::string("internal error: ") + e.what()));
  } catch (...) {
    logError("control: unknown exception");
    return errorReply(makeError(VideoErrc::kInternal, "internal error"));
  }
}

void ControlServer::runSocket() {
  zmq::pollitem_t items[] = {{socket_.handle(), 0, ZMQ_POLLIN, 0},
                             {replies_.handle(), 0, ZMQ_POLLIN, 0}};
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) break;
    }
    try {
      if (zmq::poll(items, 2, kPollPeriod) == 0) continue;
      // Replies first: they free REQ clients already waiting.
      if (items[1].revents & ZMQ_POLLIN) forwardReply();
      if (items[0].revents & ZMQ_POLLIN) receiveRequest();
    } catch (const std::exception& e) {
      // Never let an exception out of the thread loop.
      logError("control: ", e.what());
    }
  }
}

void ControlServer::receiveRequest() {
  // A REQ client's message arrives as [identity][empty][body...]: everything
  // up to the empty delimiter is the envelope the reply must carry back.
  std::vector<zmq::message_t> parts;
  do {
    parts.emplace_back();
    if (!socket_.recv(parts.back(), zmq::recv_flags::dontwait)) return;
  } while (parts.back().more());
  size_t body = 1;
  while (body < parts.size() && parts[body - 1].size() != 0) ++body;
  if (body >= parts.size()) body = 1;  // no delimiter: a DEALER that sent none
  if (body >= parts.size()) return;    // identity alone: nothing to answer
  Job job;
  // Parts after the body (a multi-part request) are ignored, as before.
  auto decoded = decodeRequest(parts[body].data(), parts[body].size());
  parts.resize(body);
  job.envelope = std::move(parts);

  proto::ControlReply reply;
  if (!decoded) {
    reply = errorReply(decoded.error());
  } else if (job.request = std::move(*decoded); answeredAtOnce(job.request)) {
    reply = answer(job.request);
  } else {
    if (enqueue(*requestCamera(job.request), job)) return;
    reply = errorReply(
        makeError(VideoErrc::kBusy, "video server busy: " + std::to_string(options_.max_pending) +
                                        " slow requests already waiting; try again"));
  }
  const std::string out = reply.SerializeAsString();
  if (!sendRouted(socket_, job.envelope, zmq::message_t(out.data(), out.size()))) {
    logWarning("control: reply dropped (client gone or not reading)");
  }
}

void ControlServer::forwardReply() {
  std::vector<zmq::message_t> parts;
  do {
    parts.emplace_back();
    if (!replies_.recv(parts.back(), zmq::recv_flags::dontwait)) return;
  } while (parts.back().more());
  zmq::message_t body = std::move(parts.back());
  parts.pop_back();
  if (!sendRouted(socket_, parts, std::move(body))) {
    logWarning("control: reply dropped (client gone or not reading)");
  }
}

bool ControlServer::enqueue(const std::string& lane, Job& job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_ || pending_ >= options_.max_pending) return false;
    auto [it, fresh] = lanes_.try_emplace(lane);
    // A lane already present is either ready or running; its worker puts it
    // back in ready_ when it finishes.
    if (fresh) ready_.push_back(lane);
    it->second.push_back(std::move(job));
    ++pending_;
  }
  work_ready_.notify_one();
  return true;
}

void ControlServer::runWorker() {
  try {
    zmq::socket_t out(context_, zmq::socket_type::push);
    out.set(zmq::sockopt::linger, 0);
    out.connect(replies_endpoint_);
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      work_ready_.wait(lock, [this] { return stopping_ || !ready_.empty(); });
      if (stopping_) return;
      const std::string lane = std::move(ready_.front());
      ready_.pop_front();
      Job job = std::move(lanes_[lane].front());
      lanes_[lane].pop_front();
      --pending_;
      lock.unlock();

      const std::string reply = answer(job.request).SerializeAsString();
      try {
        // dontwait: once the socket thread has gone, nobody reads and a
        // blocking send would hang stop().
        if (!sendRouted(out, job.envelope, zmq::message_t(reply.data(), reply.size()))) {
          logWarning("control: reply dropped (server stopping)");
        }
      } catch (const zmq::error_t& e) {
        logError("control: ", e.what());
      }

      lock.lock();
      if (stopping_) return;
      auto it = lanes_.find(lane);
      if (it == lanes_.end()) continue;
      if (it->second.empty()) {
        lanes_.erase(it);
      } else {
        ready_.push_back(lane);
        work_ready_.notify_one();
      }
    }
  } catch (const std::exception& e) {
    // Never let an exception out of a thread (only socket set-up can throw here).
    logError("control worker: ", e.what());
  }
}

}  // namespace picksight::video
