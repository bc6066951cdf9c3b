// Pins the control plane's rule, over real ZeroMQ sockets: a trigger is
// answered at once while other clients snap and read a slow feature; slow
// requests of one camera run in order, of two cameras in parallel; a full
// queue answers "busy" at once; a throwing handler is an INTERNAL reply; stop()
// returns with requests running and queued.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <zmq.hpp>

#include "picksight/transport/control_client.hpp"
#include "picksight/video_server/control_server.hpp"
#include "picksight/video_server/video_server.hpp"

using namespace std::chrono_literals;
namespace proto = picksight::proto;
using picksight::video::AcquisitionMode;
using picksight::video::CameraConfig;
using picksight::video::ControlServer;
using picksight::video::ControlServerOptions;
using picksight::video::ServerConfig;
using picksight::video::VideoServer;
using Clock = std::chrono::steady_clock;

namespace {

constexpr auto kTimeout = 10s;
// A GenICam read over a slow link, made deterministic.
constexpr auto kSlowRead = 1500ms;
// Generous: an answered-at-once trigger takes well under a millisecond, and
// one that waits behind a slow read takes up to kSlowRead.
constexpr auto kTriggerBound = 500ms;

// An on-demand source whose feature "SlowRead" takes kSlowRead to read.
class SlowFeatureSource : public picksight::video::Source {
 public:
  picksight::Result<void> open() override { return {}; }
  void close() override {}
  picksight::video::SourceInfo info() const override {
    picksight::video::SourceInfo i;
    i.vendor = "test";
    i.model = "slow feature";
    i.sensor_width = 64;
    i.sensor_height = 48;
    return i;
  }
  picksight::Result<picksight::video::SourceFrame> grab(std::chrono::milliseconds) override {
    picksight::video::SourceFrame f;
    f.image = cv::Mat(48, 64, CV_8UC1, cv::Scalar(128));
    return f;
  }
  picksight::Result<picksight::video::Feature> feature(const std::string& name) override {
    if (name != "SlowRead") return Source::feature(name);
    std::this_thread::sleep_for(kSlowRead);
    picksight::video::Feature f;
    f.name = name;
    f.value = "1";
    return f;
  }
};

// "slow" is a SlowFeatureSource, a synthetic camera beside it.
ServerConfig slowConfig() {
  ServerConfig config;
  config.frames_endpoint = "tcp://127.0.0.1:*";
  config.control_endpoint = "tcp://127.0.0.1:*";
  CameraConfig slow;
  slow.name = "slow";
  slow.uri = "slow:";
  slow.mode = AcquisitionMode::kTrigger;
  CameraConfig cam;
  cam.name = "cam";
  cam.uri = "synthetic:width=640,height=480,parts=5,seed=2";
  cam.mode = AcquisitionMode::kTrigger;
  config.cameras = {slow, cam};
  return config;
}

picksight::Result<std::unique_ptr<picksight::video::Source>> makeTestSource(
    const std::string& uri) {
  if (uri == "slow:") return std::unique_ptr<picksight::video::Source>(new SlowFeatureSource);
  return picksight::video::makeSource(uri);
}

proto::ControlRequest trigger(const std::string& camera) {
  proto::ControlRequest r;
  r.mutable_trigger()->set_camera(camera);
  return r;
}

proto::ControlRequest snap(const std::string& camera) {
  proto::ControlRequest r;
  r.mutable_snap()->set_camera(camera);
  return r;
}

proto::ControlRequest getFeature(const std::string& camera, const std::string& name) {
  proto::ControlRequest r;
  r.mutable_get_feature()->set_camera(camera);
  r.mutable_get_feature()->set_name(name);
  return r;
}

proto::ControlRequest describe(const std::string& camera) {
  proto::ControlRequest r;
  r.mutable_describe_camera()->set_camera(camera);
  return r;
}

// Opens when told; handlers wait on it.
class Gate {
 public:
  void open() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      open_ = true;
    }
    changed_.notify_all();
  }
  bool wait(std::chrono::milliseconds timeout = kTimeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    return changed_.wait_for(lock, timeout, [this] { return open_; });
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  bool open_ = false;
};

// Polls `done` until it holds or kTimeout passes.
bool eventually(const std::function<bool()>& done) {
  const auto deadline = Clock::now() + kTimeout;
  while (!done()) {
    if (Clock::now() > deadline) return false;
    std::this_thread::sleep_for(2ms);
  }
  return true;
}

// A REQ client whose request is sent now and whose reply is read later.
struct PendingClient {
  PendingClient(zmq::context_t& context, const std::string& endpoint)
      : socket(context, zmq::socket_type::req) {
    socket.set(zmq::sockopt::linger, 0);
    socket.connect(endpoint);
  }
  void send(const proto::ControlRequest& request) {
    const std::string bytes = request.SerializeAsString();
    socket.send(zmq::buffer(bytes), zmq::send_flags::none);
  }
  // The reply, or nullopt when none came within `timeout`.
  std::optional<proto::ControlReply> reply(std::chrono::milliseconds timeout = kTimeout) {
    zmq::pollitem_t item{socket.handle(), 0, ZMQ_POLLIN, 0};
    if (zmq::poll(&item, 1, timeout) == 0) return std::nullopt;
    zmq::message_t bytes;
    if (!socket.recv(bytes)) return std::nullopt;
    proto::ControlReply r;
    if (!r.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) return std::nullopt;
    return r;
  }
  zmq::socket_t socket;
};

proto::ControlReply okReply() {
  proto::ControlReply reply;
  reply.mutable_error()->set_code(proto::Error::OK);
  return reply;
}

}  // namespace

TEST_CASE("Triggers are answered at once while other clients snap and read a slow feature",
          "[video_server][control]") {
  VideoServer server(slowConfig(), makeTestSource);
  server.start();
  zmq::context_t context;

  std::atomic<bool> done{false};
  std::atomic<int> slow_reads{0};
  std::atomic<int> snaps{0};
  std::atomic<int> failures{0};
  // What the failed calls answered, for the report.
  std::mutex failed_mutex;
  std::vector<std::string> failed;
  const auto fail = [&](const std::string& what, const picksight::Error& error) {
    ++failures;
    std::lock_guard<std::mutex> lock(failed_mutex);
    failed.push_back(what + ": " + error.message);
  };
  std::thread reader([&] {
    picksight::transport::ControlClient client(context, server.controlEndpoint(), kTimeout);
    while (!done) {
      if (const auto reply = client.call(getFeature("slow", "SlowRead"))) {
        ++slow_reads;
      } else {
        fail("read", reply.error());
      }
    }
  });
  std::thread snapper([&] {
    picksight::transport::ControlClient client(context, server.controlEndpoint(), kTimeout);
    while (!done) {
      if (const auto reply = client.call(snap("cam"))) {
        ++snaps;
      } else {
        fail("snap", reply.error());
      }
    }
  });

  // Trigger both cameras throughout at least two slow reads: on a server that
  // answers one request at a time, most triggers would wait behind a read.
  picksight::transport::ControlClient robot(context, server.controlEndpoint(), kTimeout);
  std::vector<double> round_trips_ms;
  const auto deadline = Clock::now() + 30s;
  while ((slow_reads < 2 || snaps < 2) && Clock::now() < deadline) {
    for (const char* camera : {"slow", "cam"}) {
      const auto t0 = Clock::now();
      const auto reply = robot.call(trigger(camera));
      round_trips_ms.push_back(
          std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      REQUIRE(reply);
      CHECK(reply->trigger().triggered());
    }
    // Paced like a robot cycle, so the loop spans the slow reads.
    std::this_thread::sleep_for(20ms);
  }
  done = true;
  reader.join();
  snapper.join();

  CHECK(slow_reads >= 2);
  CHECK(snaps >= 2);
  for (const auto& f : failed) UNSCOPED_INFO(f);
  CHECK(failures == 0);
  REQUIRE_FALSE(round_trips_ms.empty());
  const double worst = *std::max_element(round_trips_ms.begin(), round_trips_ms.end());
  INFO(round_trips_ms.size() << " triggers, worst " << worst << " ms");
  CHECK(worst < std::chrono::duration<double, std::milli>(kTriggerBound).count());
}

TEST_CASE("Slow requests of one camera run in order and two cameras in parallel",
          "[video_server][control]") {
  std::mutex mutex;
  std::vector<std::string> ran;  // "camera/feature" in the order handled
  Gate other_camera_ran;
  zmq::context_t context;
  ControlServer control(
      context, "tcp://127.0.0.1:*",
      [&](const proto::ControlRequest& r) {
        const auto& g = r.get_feature();
        {
          std::lock_guard<std::mutex> lock(mutex);
          ran.push_back(g.camera() + "/" + g.name());
        }
        // camA's first request holds its lane until camB's has run: only a
        // second worker can run it.
        if (g.camera() == "camA" && g.name() == "1") other_camera_ran.wait();
        if (g.camera() == "camB") other_camera_ran.open();
        return okReply();
      },
      ControlServerOptions{4, 16});
  control.start();

  // One DEALER sends everything without waiting, so arrival order is known.
  zmq::socket_t dealer(context, zmq::socket_type::dealer);
  dealer.set(zmq::sockopt::linger, 0);
  dealer.connect(control.boundEndpoint());
  const std::vector<std::pair<std::string, std::string>> sent = {
      {"camA", "1"}, {"camA", "2"}, {"camB", "1"}, {"camA", "3"}};
  for (const auto& [camera, name] : sent) {
    const std::string bytes = getFeature(camera, name).SerializeAsString();
    dealer.send(zmq::message_t(), zmq::send_flags::sndmore);
    dealer.send(zmq::buffer(bytes), zmq::send_flags::none);
  }
  for (size_t i = 0; i < sent.size(); ++i) {
    zmq::pollitem_t item{dealer.handle(), 0, ZMQ_POLLIN, 0};
    REQUIRE(zmq::poll(&item, 1, kTimeout) == 1);
    zmq::message_t delimiter, body;
    REQUIRE(dealer.recv(delimiter));
    CHECK(delimiter.size() == 0);
    REQUIRE(dealer.recv(body));
  }
  std::vector<std::string> cam_a;
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& r : ran) {
      if (r.rfind("camA/", 0) == 0) cam_a.push_back(r);
    }
  }
  CHECK(cam_a == std::vector<std::string>{"camA/1", "camA/2", "camA/3"});
  control.stop();
}

TEST_CASE("A full queue of slow requests answers busy at once and recovers",
          "[video_server][control]") {
  zmq::context_t context;
  Gate release;
  std::atomic<int> started{0};
  ControlServer control(
      context, "tcp://127.0.0.1:*",
      [&](const proto::ControlRequest& r) {
        if (r.has_describe_camera()) {
          ++started;
          release.wait();
        }
        return okReply();
      },
      ControlServerOptions{1, 2});
  control.start();

  // One running; of three more, two are queued and the last to arrive is
  // refused, while the running one still holds the only worker.
  std::vector<std::unique_ptr<PendingClient>> clients;
  for (int i = 0; i < 4; ++i) {
    clients.push_back(std::make_unique<PendingClient>(context, control.boundEndpoint()));
    clients.back()->send(describe("cam"));
    if (i == 0) REQUIRE(eventually([&] { return started == 1; }));
  }
  size_t refused = 0;
  std::optional<proto::ControlReply> busy;
  REQUIRE(eventually([&] {
    for (size_t i = 1; i < clients.size() && !busy; ++i) {
      busy = clients[i]->reply(0ms);
      refused = i;
    }
    return busy.has_value();
  }));
  CHECK(busy->error().code() == proto::Error::BUSY);
  CHECK_THAT(busy->error().text(), Catch::Contains("busy"));
  picksight::transport::ControlClient client(context, control.boundEndpoint(), kTimeout);
  CHECK(client.call(trigger("cam")));

  release.open();
  for (size_t i = 0; i < clients.size(); ++i) {
    if (i == refused) continue;
    const auto reply = clients[i]->reply();
    REQUIRE(reply);
    CHECK(reply->error().code() == proto::Error::OK);
  }
  CHECK(client.call(describe("cam")));
}

TEST_CASE("A throwing handler is an INTERNAL reply and the server goes on",
          "[video_server][control]") {
  zmq::context_t context;
  ControlServer control(context, "tcp://127.0.0.1:*", [](const proto::ControlRequest& r) {
    if (r.has_snap()) throw std::runtime_error("boom");
    return okReply();
  });
  control.start();
  picksight::transport::ControlClient client(context, control.boundEndpoint(), kTimeout);
  const auto thrown = client.call(snap("cam"));
  REQUIRE_FALSE(thrown);
  CHECK(thrown.error().code == picksight::transport::ControlErrc::kInternal);
  CHECK_THAT(thrown.error().message, Catch::Contains("boom"));
  CHECK(client.call(trigger("cam")));
  CHECK(client.call(describe("cam")));
}

TEST_CASE("stop returns with a slow request running and others queued", "[video_server][control]") {
  zmq::context_t context;
  Gate release;
  std::atomic<int> started{0};
  auto control = std::make_unique<ControlServer>(
      context, "tcp://127.0.0.1:*",
      [&](const proto::ControlRequest&) {
        ++started;
        release.wait(300ms);  // a request that finishes on its own, late
        return okReply();
      },
      ControlServerOptions{1, 8});
  control->start();
  std::vector<std::unique_ptr<PendingClient>> clients;
  for (int i = 0; i < 3; ++i) {
    clients.push_back(std::make_unique<PendingClient>(context, control->boundEndpoint()));
    clients.back()->send(describe("cam"));
  }
  REQUIRE(eventually([&] { return started == 1; }));
  const auto t0 = Clock::now();
  control->stop();
  CHECK(Clock::now() - t0 < kTimeout);
  // Nobody is answered after stop(): the queued clients time out.
  CHECK(started == 1);
  control.reset();
}
