// End-to-end cell fixture (see cell_fixture.hpp).
#include "cell_fixture.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>

#include "picksight/common/angles.hpp"
#include "picksight/common/text.hpp"
#include "picksight/transport/control_client.hpp"

namespace picksight::e2e {

using tool_support::LineClient;
using tool_support::Subprocess;
using transport::ControlClient;
using transport::FrameSubscriber;

using namespace std::chrono_literals;

std::string binPath(const std::string& name) { return std::string(PICKSIGHT_BIN_DIR) + "/" + name; }

VideoServerProcess::VideoServerProcess(std::vector<std::string> args, const std::string& log_file) {
  std::vector<std::string> argv = {binPath("picksight-video-server"), "--frames",
                                   "tcp://127.0.0.1:*", "--control", "tcp://127.0.0.1:*"};
  argv.insert(argv.end(), args.begin(), args.end());
  if (!log_file.empty()) {
    // The shell only redirects and execs: the child is still the server.
    argv.insert(argv.begin(), {"/bin/sh", "-c", "exec \"$@\" 2>\"$0\"", log_file});
  }
  process = std::make_unique<Subprocess>(argv);
  auto f = process->waitForLine("frames ", 10s);
  REQUIRE(f);
  auto c = process->waitForLine("control ", 10s);
  REQUIRE(c);
  frames = *f;
  control = *c;
}

VisionProcess::VisionProcess(const VideoServerProcess& server, const std::string& camera,
                             const std::string& given_data_dir,
                             const std::vector<std::string>& extra_args) {
  if (given_data_dir.empty()) {
    char dir[] = "/tmp/picksight-e2e-XXXXXX";
    REQUIRE(::mkdtemp(dir) != nullptr);
    data_dir = dir;
  } else {
    data_dir = given_data_dir;
    own_data_dir = false;
  }
  std::vector<std::string> argv{binPath("picksight-vision"),
                                "--frames",
                                server.frames,
                                "--control",
                                server.control,
                                "--camera",
                                camera,
                                "--robot-port",
                                "0",
                                "--bind",
                                "127.0.0.1",
                                "--data-dir",
                                data_dir};
  argv.insert(argv.end(), extra_args.begin(), extra_args.end());
  process = std::make_unique<Subprocess>(argv);
  const auto portLine = [&](const std::string& prefix) {
    auto port = process->waitForLine(prefix, 10s);
    REQUIRE(port);
    auto value = parseInt(*port);
    REQUIRE(value);
    return static_cast<uint16_t>(*value);
  };
  robot_port = portLine("robot ");
  if (std::find(extra_args.begin(), extra_args.end(), "--setup-port") != extra_args.end()) {
    setup_port = portLine("setup ");
  }
  // Lines up to "ready"; "results <endpoint>" among them unless turned off.
  for (;;) {
    auto line = process->readLine(10s);
    REQUIRE(line);
    if (line->rfind("results ", 0) == 0) results_endpoint = line->substr(8);
    if (*line == "ready") break;
  }
}

VisionProcess::~VisionProcess() {
  process.reset();
  std::error_code ignored;
  if (own_data_dir) std::filesystem::remove_all(data_dir, ignored);
}

LineClient VisionProcess::connect() const {
  auto c = LineClient::connect("127.0.0.1", robot_port, 5s);
  REQUIRE(c);
  return std::move(*c);
}

PhotographCell::PhotographCell(const std::string& scene_file)
    : server({"--source",
              "cam0=file:" + (scene_file.rfind('/', 0) == 0
                                  ? scene_file
                                  : std::string(PICKSIGHT_TEST_DATA_DIR) + "/scenes/" + scene_file),
              "--mode", "trigger"}),
      vision(server),
      robot(vision.connect()) {}

std::string PhotographCell::ask(const std::string& line) {
  auto reply = robot.request(line, 20s);
  REQUIRE(reply);
  return *reply;
}

CommandResult run(const std::vector<std::string>& argv) {
  Subprocess p(argv);
  CommandResult r;
  while (auto line = p.readLine(10s)) r.out += *line + "\n";
  auto status = p.wait(10s);
  REQUIRE(status);
  r.exit_code = WIFEXITED(*status) ? WEXITSTATUS(*status) : -1;
  return r;
}

std::optional<Frame> receiveUntil(FrameSubscriber& subscriber,
                                  const std::function<bool(const Frame&)>& accept, int tries) {
  for (int i = 0; i < tries; ++i) {
    auto f = subscriber.receive(2s);
    if (f && accept(*f)) return f;
  }
  return std::nullopt;
}

uint64_t waitForSubscription(const VideoServerProcess& server, FrameSubscriber& subscriber,
                             const std::string& camera) {
  zmq::context_t context;
  ControlClient control(context, server.control);
  proto::ControlRequest trigger;
  trigger.mutable_trigger()->set_camera(camera);
  for (int i = 0; i < 50; ++i) {
    REQUIRE(control.call(trigger));
    if (auto frame = subscriber.receive(200ms)) return frame->info.sequence;
  }
  FAIL("no frame of " << camera << " reached the subscriber");
  return 0;
}

std::vector<double> replyNumbers(const std::string& reply, size_t expected) {
  const auto w = splitFields(reply, " ");
  REQUIRE(w.size() == expected + 1);
  REQUIRE(w[0] == "OK");
  std::vector<double> out;
  for (size_t i = 1; i < w.size(); ++i) {
    auto v = parseDouble(w[i]);
    REQUIRE(v);
    out.push_back(*v);
  }
  return out;
}

std::vector<Pose> parseLocateReply(const std::string& reply) {
  const auto words = splitFields(reply, " ");
  REQUIRE(words.size() >= 2);
  REQUIRE(words[0] == "OK");
  const auto n = parseInt(words[1]);
  REQUIRE(n);
  REQUIRE(words.size() == 2 + 3 * static_cast<size_t>(*n));
  std::vector<Pose> poses;
  for (size_t i = 2; i < words.size(); i += 3) {
    auto x = parseDouble(words[i]);
    auto y = parseDouble(words[i + 1]);
    auto rz = parseDouble(words[i + 2]);
    REQUIRE((x && y && rz));
    poses.push_back({*x, *y, *rz});
  }
  return poses;
}

std::vector<Pose> imagePoses(const std::string& reply) {
  auto poses = parseLocateReply(reply);
  for (auto& p : poses) {
    p.y = -p.y;
    p.rz = normalizeDeg(-p.rz);  // a recognized part's rz may be negative
  }
  return poses;
}

}  // namespace picksight::e2e
