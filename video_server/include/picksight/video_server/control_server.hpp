// The control socket: decodes ControlRequest messages from REQ clients and
// sends back the handler's ControlReply, with slow requests on worker threads.
//
// The rule: the trigger path never waits behind a slow request.
// * The socket thread owns the ROUTER socket (REQ clients speak to it
//   unchanged) and answers at once, itself, the requests that only take a
//   camera's mutex for a moment: trigger, list_cameras, statistics, and
//   anything malformed or unknown (answeredAtOnce() in control_request.hpp).
// * Everything that can be slow, because it touches a driver or waits for a
//   frame (snap, list/get/set feature, describe, open/close, ROI, size,
//   format, mode), goes to a queue served by worker threads. Requests for one
//   camera form one lane that at most one worker runs at a time, so they run
//   in arrival order; lanes of different cameras run in parallel. A client's
//   own requests stay in order anyway: a REQ client waits for each reply.
// * A worker hands its reply, with the client's routing envelope, to the
//   socket thread over an inproc PUSH/PULL pair (a ZeroMQ socket belongs to
//   one thread); the socket thread polls both sockets.
// * At most `max_pending` slow requests wait (not counting those running); one
//   more gets an immediate BUSY reply (VideoErrc::kBusy).
// * The handler runs on either thread and must be safe to call concurrently;
//   no exception leaves a thread (a throwing handler becomes an INTERNAL reply).
// * stop() joins every thread: queued requests are dropped (their REQ clients
//   time out), a request already running finishes first (the handler's own
//   timeouts bound that, 5 s at most for a feature) and its reply is dropped.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <zmq.hpp>

#include "picksight.pb.h"
#include "picksight/transport/curve_server.hpp"

namespace picksight::video {

struct ControlServerOptions {
  size_t workers = 4;                             // parallel lanes (cameras) of slow requests
  size_t max_pending = 64;                        // slow requests waiting for a worker
  const transport::CurveServer* curve = nullptr;  // makes the ROUTER a CURVE server
};

class ControlServer {
 public:
  using Handler = std::function<proto::ControlReply(const proto::ControlRequest&)>;

  // Binds at once so a bad endpoint fails at start-up.
  ControlServer(zmq::context_t& context, const std::string& endpoint, Handler handler,
                ControlServerOptions options = {});
  ~ControlServer();
  ControlServer(const ControlServer&) = delete;
  ControlServer& operator=(const ControlServer&) = delete;

  const std::string& boundEndpoint() const { return bound_endpoint_; }
  void start();
  void stop();

 private:
  // A slow request waiting for a worker: the client's envelope and the request.
  struct Job {
    std::vector<zmq::message_t> envelope;
    proto::ControlRequest request;
  };

  void runSocket();
  void receiveRequest();
  void forwardReply();
  void runWorker();
  // Moves `job` into its lane's queue; false (job untouched) when the queue
  // is full or the server is stopping.
  bool enqueue(const std::string& lane, Job& job);
  // The handler's reply, or an INTERNAL one if it threw.
  proto::ControlReply answer(const proto::ControlRequest& request);

  zmq::context_t& context_;
  const Handler handler_;
  const ControlServerOptions options_;
  zmq::socket_t socket_;   // ROUTER; socket thread only (after start)
  zmq::socket_t replies_;  // PULL of the workers' replies; socket thread only
  std::string bound_endpoint_;
  std::string replies_endpoint_;
  std::thread socket_thread_;
  std::vector<std::thread> workers_;

  std::mutex mutex_;  // guards everything below
  std::condition_variable work_ready_;
  bool stopping_ = false;
  // Lanes with queued or running jobs, by camera; a lane is in ready_ when it
  // has a job and no worker runs it.
  std::map<std::string, std::deque<Job>> lanes_;
  std::deque<std::string> ready_;
  size_t pending_ = 0;  // jobs queued in lanes_, not yet running
};

}  // namespace picksight::video
