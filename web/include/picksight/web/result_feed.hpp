// One vision app for the web server: its results stream (a SUB socket on the
// app's results endpoint, decoded to VisionResult), the counters /metrics
// shows, each result's JSON for the /events clients and /api/results, and
// the robot (or setup) connection that commands from the page go through.
//
// Threading: the feed's thread owns the SUB socket and its monitor, and
// keeps the latest result and the counters; readers take snapshots under
// mutex_. The JSON of a LOCATE of many parts costs about as much CPU as the
// LOCATE, so it is made only while an /events client is connected, by a
// converter thread at SCHED_IDLE (never on a core a vision pass wants), for
// the newest result only: a page that cannot be served in time skips
// results, never delays a robot. When that thread has had no core for
// kResultsStarved, the feed's thread converts at its own priority, so a
// saturated machine still shows results. latestJson() converts on demand
// in the caller's thread. command() holds line_mutex_ for one request and
// reply, on a kept connection (so WHY speaks of the page's last LOCATE).
//
// A result marked `changed` is a change made at a robot's, a PLC's or the
// set-up port's request: the feed's thread hands it to the change handler
// (the web's audit trail), unless it came over the web's own command
// connection (the page's changes are recorded by the web itself, with
// their user); one that worked on no frame is not shown as a result.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <zmq.hpp>

#include "picksight/common/result.hpp"
#include "picksight/tool_support/line_client.hpp"
#include "picksight/web/event_hub.hpp"
#include "picksight/web/web_options.hpp"
#include "results.pb.h"

namespace picksight::web {

// Upper bounds (seconds) of the request-time histogram's buckets (+Inf after).
constexpr std::array<double, 11> kRequestBuckets = {0.001, 0.0025, 0.005, 0.01, 0.025, 0.05,
                                                    0.1,   0.25,   0.5,   1.0,  2.5};

// Counts and time histogram of one request kind (LOCATE, LEARN...).
struct RequestFigures {
  uint64_t count = 0;
  double seconds_sum = 0;
  std::array<uint64_t, kRequestBuckets.size()> buckets{};  // cumulative at read time
};

// How long a result may wait for the idle-priority converter before the
// feed's thread converts it itself (as CameraFeed's JPEGs, kEncoderStarved).
constexpr std::chrono::milliseconds kResultsStarved{3000};

// The longest robot line the page may send (bytes, without the newline);
// a piece of a job import (JOB IMPORT, access_policy.hpp) may be longer,
// as the robot port allows.
constexpr size_t kMaxCommandBytes = 256;
constexpr size_t kMaxJobPieceBytes = 4000;

class ResultFeed {
 public:
  // Called on the feed's thread for each change another client made.
  using ChangeHandler = std::function<void(const proto::VisionResult& change)>;
  ResultFeed(zmq::context_t& context, VisionAppEndpoint app, EventHub& events,
             ChangeHandler on_change = {});
  ~ResultFeed();
  ResultFeed(const ResultFeed&) = delete;
  ResultFeed& operator=(const ResultFeed&) = delete;

  const std::string& name() const { return app_.name; }

  // The /api/apps entry: name, camera, connected, last_result_id.
  std::string camera() const;
  bool connected() const { return connected_.load(); }
  uint64_t lastResultId() const;
  // The latest result (null before the first) and its JSON (made on the
  // first call after a result no /events client saw; empty before the first).
  std::shared_ptr<const proto::VisionResult> latest() const;
  std::string latestJson() const;
  std::map<std::string, RequestFigures> figures() const;

  // Takes one robot-protocol line to the app and returns its reply line.
  // Lines over `max_bytes` or with CR/LF are refused (kBadRequest); a
  // dead app is kUnreachable.
  Result<std::string> command(const std::string& line, size_t max_bytes = kMaxCommandBytes);

  // Handles one received result as the thread does (also for tests).
  void accept(proto::VisionResult result);
  // Whether a result's client ("robot 127.0.0.1:41234") is one of the
  // recent command connections of this feed.
  bool ownClient(const std::string& client) const;

  void stop();

 private:
  void run(zmq::context_t& context);
  void convertLoop();
  // Converts the pending result, if any, and publishes it unless a newer
  // one was published meanwhile.
  void publishPending();
  bool pendingStarved() const;

  const VisionAppEndpoint app_;
  EventHub& events_;

  mutable std::mutex mutex_;
  std::shared_ptr<const proto::VisionResult> latest_;  // under mutex_
  mutable std::string latest_json_;                    // under mutex_; empty: not made yet
  std::map<std::string, RequestFigures> figures_;      // under mutex_
  // The newest result not yet sent as an event, its number in arrival order
  // and since when it waits; a lock of its own, so that the idle-priority
  // converter never holds the one the HTTP threads read under.
  mutable std::mutex convert_mutex_;
  std::condition_variable convert_wake_;
  std::shared_ptr<const proto::VisionResult> pending_;   // under convert_mutex_
  uint64_t pending_number_ = 0;                          // under convert_mutex_
  std::chrono::steady_clock::time_point pending_since_;  // under convert_mutex_
  bool stopping_ = false;                                // under convert_mutex_
  std::mutex publish_mutex_;                             // one event published at a time, in order
  uint64_t published_number_ = 0;                        // under publish_mutex_

  const ChangeHandler on_change_;

  std::mutex line_mutex_;
  tool_support::LineClient line_;  // under line_mutex_
  // This end of the last few command connections ("127.0.0.1:41234"): a
  // change's record may arrive after its connection was replaced.
  mutable std::mutex own_mutex_;
  std::deque<std::string> own_endpoints_;  // under own_mutex_

  std::atomic<bool> connected_{false};
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::thread convert_thread_;
};

}  // namespace picksight::web
