// The vision app's results stream (docs/PROTOCOL.md, "Results stream"): one
// VisionResult per request on a ZeroMQ PUB socket, two frames (topic = the
// app's name, then the message).
//
// Never on the robot's critical path: publish() only queues the record (a
// full queue drops the oldest record but a change, and counts it); a publisher thread
// builds the message (regions, outlines, rejections) and sends it without
// blocking (a small send high-water mark: a slow subscriber loses
// messages, never delays the cell). While nobody subscribes to the topic
// (the socket is an XPUB and sees the subscriptions), no message is built:
// the next request gets the CPU.
//
// Threading: publish() from any thread; the socket belongs to the
// publisher thread. ZeroMQ and Protobuf stay inside this library.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "picksight/results/request_record.hpp"

namespace picksight::results {

struct ResultsOptions {
  std::string bind = "tcp://127.0.0.1:*";  // "none": no results stream
  std::string app;                         // topic and VisionResult.app
  int send_hwm = 16;                       // messages ZeroMQ keeps per subscriber
  size_t queue = 8;                        // records waiting for the publisher thread
};

class ResultsPublisher {
 public:
  // Binds at once; throws std::runtime_error naming the endpoint.
  explicit ResultsPublisher(ResultsOptions options);
  ~ResultsPublisher();
  ResultsPublisher(const ResultsPublisher&) = delete;
  ResultsPublisher& operator=(const ResultsPublisher&) = delete;

  // The bound endpoint, with the port resolved ("tcp://127.0.0.1:40123").
  const std::string& endpoint() const;
  // Queues one request's record; returns at once.
  void publish(std::shared_ptr<const RequestRecord> record);

  uint64_t sent() const;     // messages handed to ZeroMQ
  uint64_t dropped() const;  // records dropped by a full queue or a full socket
  // Records not built because nobody subscribed to the topic.
  uint64_t unwatched() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// What to run once a request's reply has been sent: fill in the reply and
// the time since `received`, then queue `record` on `results` (if any).
std::function<void(const std::string& reply)> publishWhenSent(
    std::shared_ptr<RequestRecord> record, std::chrono::steady_clock::time_point received,
    ResultsPublisher* results);

}  // namespace picksight::results
