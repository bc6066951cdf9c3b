// The results subscriber, its counters and the command connection.
#include "picksight/web/result_feed.hpp"

#include <algorithm>
#include <sstream>
#include <string>

#include "picksight/common/log.hpp"
#include "picksight/common/text.hpp"
#include "picksight/web/idle_priority.hpp"
#include "picksight/web/proto_json.hpp"
#include "picksight/web/web_errors.hpp"

namespace picksight::web {

using tool_support::LineClient;

namespace {
// Whether the change is a job loaded (`JOB LOAD <name>`, any case): what
// every part drawn before it was found with is no longer in force.
bool jobLoad(const proto::VisionResult& result) {
  if (result.request() != "JOB") return false;
  std::istringstream words(result.request_line());
  std::string command;
  std::string sub;
  words >> command >> sub;
  return toUpper(sub) == "LOAD";
}
using namespace std::chrono_literals;

constexpr auto kConnectTimeout = 2s;
// A LOCATE in trigger mode waits for its frame; LEARN and COMPUTE take
// longer than a robot request: the page waits up to this for a reply.
constexpr auto kReplyTimeout = 10s;
// A result message is a few hundred kilobytes at most (1024 regions of 512
// points); anything bigger is not one of ours.
constexpr int64_t kMaxResultBytes = 16 << 20;

// Follows the SUB socket's connection to the app.
class ConnectionMonitor : public zmq::monitor_t {
 public:
  explicit ConnectionMonitor(std::atomic<bool>& connected) : connected_(connected) {}
  void on_event_connected(const zmq_event_t&, const char*) override { connected_ = true; }
  void on_event_disconnected(const zmq_event_t&, const char*) override { connected_ = false; }

 private:
  std::atomic<bool>& connected_;
};

// The line a vision app sends when it closes a connection for idleness
// (docs/PROTOCOL.md, error 16): never the reply to a request.
bool isIdleClose(const std::string& reply) { return reply.rfind("ERROR 16 ", 0) == 0; }

}  // namespace

ResultFeed::ResultFeed(zmq::context_t& context, VisionAppEndpoint app, EventHub& events,
                       ChangeHandler on_change)
    : app_(std::move(app)), events_(events), on_change_(std::move(on_change)) {
  convert_thread_ = std::thread([this] { convertLoop(); });
  if (app_.results != "none") thread_ = std::thread([this, &context] { run(context); });
}

ResultFeed::~ResultFeed() { stop(); }

void ResultFeed::stop() {
  stop_ = true;
  {
    std::lock_guard<std::mutex> lock(convert_mutex_);
    stopping_ = true;
    convert_wake_.notify_all();
  }
  if (thread_.joinable()) thread_.join();
  if (convert_thread_.joinable()) convert_thread_.join();
}

void ResultFeed::convertLoop() {
  runAtIdlePriority("vision app " + app_.name + ": results to JSON");
  std::unique_lock<std::mutex> lock(convert_mutex_);
  while (true) {
    convert_wake_.wait(lock, [&] { return pending_ || stopping_; });
    if (stopping_) return;
    lock.unlock();
    publishPending();
    lock.lock();
  }
}

bool ResultFeed::pendingStarved() const {
  std::lock_guard<std::mutex> lock(convert_mutex_);
  return pending_ && std::chrono::steady_clock::now() - pending_since_ >= kResultsStarved;
}

void ResultFeed::publishPending() {
  std::shared_ptr<const proto::VisionResult> result;
  uint64_t number = 0;
  {
    std::lock_guard<std::mutex> lock(convert_mutex_);
    if (!pending_) return;
    result = std::move(pending_);
    pending_.reset();
    number = pending_number_;
  }
  std::string json = protoJsonText(*result);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (latest_ == result) latest_json_ = json;
  }
  // The converter and a starved feed thread may both be converting: an
  // older result is never sent after a newer one.
  std::lock_guard<std::mutex> lock(publish_mutex_);
  if (number <= published_number_) return;
  published_number_ = number;
  events_.publish("result", json);
}

void ResultFeed::run(zmq::context_t& context) {
  try {
    zmq::socket_t socket(context, zmq::socket_type::sub);
    socket.set(zmq::sockopt::rcvhwm, 64);
    socket.set(zmq::sockopt::maxmsgsize, kMaxResultBytes);
    socket.set(zmq::sockopt::linger, 0);
    ConnectionMonitor monitor(connected_);
    // inproc names are per context: the app's name keeps them apart.
    monitor.init(socket, "inproc://picksight-web-results-" + app_.name,
                 ZMQ_EVENT_CONNECTED | ZMQ_EVENT_DISCONNECTED);
    socket.set(zmq::sockopt::subscribe, app_.name);
    socket.connect(app_.results);
    zmq::pollitem_t item{socket.handle(), 0, ZMQ_POLLIN, 0};
    while (!stop_) {
      monitor.check_event(0);
      if (pendingStarved()) publishPending();  // the converter has had no core
      zmq::poll(&item, 1, 200ms);
      if (!(item.revents & ZMQ_POLLIN)) continue;
      zmq::message_t topic;
      zmq::message_t body;
      if (!socket.recv(topic, zmq::recv_flags::dontwait)) continue;
      bool two_parts = topic.more() && socket.recv(body, zmq::recv_flags::dontwait);
      while (socket.get(zmq::sockopt::rcvmore)) {  // drop any extra parts
        zmq::message_t extra;
        (void)socket.recv(extra, zmq::recv_flags::dontwait);
        two_parts = false;
      }
      if (!two_parts || topic.to_string_view() != app_.name) continue;
      proto::VisionResult result;
      if (!result.ParseFromArray(body.data(), static_cast<int>(body.size()))) {
        logWarning("vision app ", app_.name, ": malformed result message skipped");
        continue;
      }
      if (result.changed()) {
        if (on_change_ && !ownClient(result.client())) on_change_(result);
        // A change that worked on no frame (TOLERANCE, FORGET...) is the
        // trail's, not a result for the page to draw; but a job loaded
        // changes what every part drawn was found with (models, settings,
        // calibration): the page then draws nothing from before it, and its
        // binarized view takes the job's settings.
        if (result.frame_width() == 0 && !jobLoad(result)) continue;
      }
      accept(std::move(result));
    }
    monitor.abort();
  } catch (const std::exception& e) {
    logError("vision app ", app_.name, ": results feed stopped: ", e.what());
  }
  connected_ = false;
}

void ResultFeed::accept(proto::VisionResult result) {
  if (result.app().empty()) result.set_app(app_.name);
  auto shared = std::make_shared<const proto::VisionResult>(std::move(result));
  // The JSON of a LOCATE of 20 parts with their outlines took as much CPU
  // as the LOCATE itself (protobuf prints and re-reads every double), and
  // was made right when the robot's next request starts: now only for an
  // /events client, by the idle-priority converter, else when /api/results
  // asks for it.
  const bool wanted = events_.clients() > 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    RequestFigures& f = figures_[shared->request().empty() ? "unknown" : shared->request()];
    ++f.count;
    const double seconds = shared->elapsed_ms() / 1000.0;
    f.seconds_sum += seconds;
    for (size_t i = 0; i < kRequestBuckets.size(); ++i)
      if (seconds <= kRequestBuckets[i]) ++f.buckets[i];
    latest_ = shared;
    latest_json_.clear();
  }
  if (!wanted) return;
  std::lock_guard<std::mutex> lock(convert_mutex_);
  if (!pending_) pending_since_ = std::chrono::steady_clock::now();
  pending_ = std::move(shared);  // replaces one the converter has not taken yet
  ++pending_number_;
  convert_wake_.notify_one();
}

bool ResultFeed::ownClient(const std::string& client) const {
  // "<port label> <address>:<port>"
  const size_t space = client.find(' ');
  const std::string endpoint = space == std::string::npos ? client : client.substr(space + 1);
  std::lock_guard<std::mutex> lock(own_mutex_);
  return std::find(own_endpoints_.begin(), own_endpoints_.end(), endpoint) != own_endpoints_.end();
}

std::string ResultFeed::camera() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_ ? latest_->camera() : std::string();
}

uint64_t ResultFeed::lastResultId() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_ ? latest_->request_id() : 0;
}

std::shared_ptr<const proto::VisionResult> ResultFeed::latest() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

std::string ResultFeed::latestJson() const {
  std::shared_ptr<const proto::VisionResult> result;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!latest_ || !latest_json_.empty()) return latest_json_;
    result = latest_;
  }
  std::string json = protoJsonText(*result);  // outside the lock: the feed goes on meanwhile
  std::lock_guard<std::mutex> lock(mutex_);
  if (latest_ == result) latest_json_ = json;
  return json;
}

std::map<std::string, RequestFigures> ResultFeed::figures() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return figures_;
}

Result<std::string> ResultFeed::command(const std::string& line, size_t max_bytes) {
  if (line.empty()) return makeError(WebErrc::kBadRequest, "empty command line");
  if (line.size() > max_bytes)
    return makeError(WebErrc::kBadRequest,
                     "command line longer than " + std::to_string(max_bytes) + " bytes");
  if (line.find_first_of("\r\n") != std::string::npos)
    return makeError(WebErrc::kBadRequest, "command line contains CR or LF");
  std::lock_guard<std::mutex> lock(line_mutex_);
  // A kept connection the app has closed meanwhile (restart, idle timeout)
  // fails at once, or answers with the line the app sent as it closed it
  // (ERROR 16 after its idle timeout, waiting unread in our socket): then
  // once more on a fresh one. The app executes nothing on a connection it
  // closes for idleness, so the resend cannot run a command twice. A reply
  // that timed out is never sent again (the app may have acted on it).
  Error last;
  for (int attempt = 0; attempt < 2; ++attempt) {
    const bool reused = line_.isOpen();
    if (!reused) {
      auto client = LineClient::connect(app_.host, app_.port, kConnectTimeout);
      if (!client) {
        return makeError(WebErrc::kUnreachable, "vision app " + app_.name + " (" + app_.host + ":" +
                                                    std::to_string(app_.port) +
                                                    "): " + client.error().message);
      }
      line_ = std::move(*client);
      std::lock_guard<std::mutex> own(own_mutex_);
      own_endpoints_.push_back(line_.localEndpoint());
      if (own_endpoints_.size() > 8) own_endpoints_.pop_front();
    }
    const auto start = std::chrono::steady_clock::now();
    auto reply = line_.request(line, kReplyTimeout);
    if (reply && !(reused && isIdleClose(*reply))) return reply;
    last = reply ? makeError(WebErrc::kUnreachable, *reply) : reply.error();
    line_.close();
    if (!reused || std::chrono::steady_clock::now() - start > 1s) break;
  }
  return makeError(WebErrc::kUnreachable, "vision app " + app_.name + ": " + last.message);
}

}  // namespace picksight::web
