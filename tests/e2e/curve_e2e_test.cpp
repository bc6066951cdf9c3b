// CURVE end to end: keys from picksight-keygen, a real video server with an
// allow-list, and listed, unlisted and plain clients; picksight-cam and the
// vision app with keys.
#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "cell_fixture.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/transport/curve_keys.hpp"
#include "picksight/transport/frame_seal.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::transport;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {

// server.key(_secret) and stranger.key(_secret) in the directory,
// listed.key(_secret) in its clients/ (the server's allow-list).
struct Keys {
  test::TempDir dir;
  std::string clients = dir.file("clients");
  std::string stranger_public;
  Keys() {
    std::filesystem::create_directory(clients);
    REQUIRE(run({binPath("picksight-keygen"), "--dir", dir.path().string(), "server"}).exit_code ==
            0);
    REQUIRE(run({binPath("picksight-keygen"), "--dir", clients, "listed"}).exit_code == 0);
    auto stranger = run({binPath("picksight-keygen"), "--dir", dir.path().string(), "stranger"});
    REQUIRE(stranger.exit_code == 0);
    stranger_public = stranger.out.substr(0, kZ85KeyLength);
  }
  std::string serverSecret() const { return dir.file("server.key_secret"); }
  std::string serverPublic() const { return dir.file("server.key"); }
  std::string listedSecret() const { return clients + "/listed.key_secret"; }
  std::string strangerSecret() const { return dir.file("stranger.key_secret"); }
  CurveClientKeys client(const std::string& secret) const {
    auto keys = loadClientKeys(secret, serverPublic());
    REQUIRE(keys);
    return *keys;
  }
  std::vector<std::string> serverArgs() const {
    return {"--curve-secret-key", serverSecret(), "--curve-clients", clients};
  }
};

std::string fileText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

proto::ControlRequest listCameras() {
  proto::ControlRequest request;
  request.mutable_list_cameras();
  return request;
}

}  // namespace

TEST_CASE(
    "CURVE: a listed client gets frames and replies while unlisted and plain ones get nothing",
    "[e2e][curve]") {
  Keys keys;
  const std::string log = keys.dir.file("server.log");
  std::vector<std::string> args = {"--source", "cam0=synthetic:width=320,height=240", "--fps",
                                   "30"};
  for (const auto& a : keys.serverArgs()) args.push_back(a);
  // The context ends after the server: no handshake is left half done.
  zmq::context_t context;
  VideoServerProcess server(args, log);
  // Those that must get nothing connect first: they have at least as long
  // as the listed client, whose frames are the test's positive control.
  // The frames' socket is plain (frames are sealed once each, not
  // encrypted per subscriber): the unlisted and the plain subscribers
  // receive the sealed messages but cannot open them, and the unlisted one
  // is refused the key on the control socket.
  FrameSubscriber unlisted(context, server.frames, "cam0", 4, keys.client(keys.strangerSecret()),
                           server.control);
  FrameSubscriber plain(context, server.frames, "cam0");
  FrameSubscriber listed(context, server.frames, "cam0", 4, keys.client(keys.listedSecret()),
                         server.control);

  int listed_frames = 0, unlisted_frames = 0, plain_frames = 0;
  bool refusal_logged = false;
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (std::chrono::steady_clock::now() < deadline &&
         (listed_frames < 10 || !refusal_logged || unlisted.framesUnopened() == 0 ||
          plain.malformedMessages() == 0)) {
    if (listed.receive(100ms)) ++listed_frames;
    while (unlisted.receive(0ms)) ++unlisted_frames;
    while (plain.receive(0ms)) ++plain_frames;
    refusal_logged = fileText(log).find(keys.stranger_public) != std::string::npos;
  }
  INFO("server log:\n" << fileText(log));
  CHECK(listed_frames >= 10);
  CHECK(listed.malformedMessages() == 0);
  CHECK(refusal_logged);
  CHECK(unlisted_frames == 0);
  CHECK(unlisted.framesUnopened() > 0);  // sealed frames reached it, unopened
  CHECK(plain_frames == 0);
  CHECK(plain.malformedMessages() > 0);
  CHECK_THAT(fileText(log), Catch::Contains("only the clients listed in"));

  // On the wire: no part of a frame's header or pixels in clear. The
  // synthetic camera's background is one grey level (pixels of one value
  // over most of the frame); sealed, the bytes look random.
  zmq::socket_t raw(context, zmq::socket_type::sub);
  raw.set(zmq::sockopt::subscribe, "cam0");
  raw.set(zmq::sockopt::linger, 0);
  raw.set(zmq::sockopt::rcvtimeo, 5000);
  raw.connect(server.frames);
  zmq::message_t topic, envelope, pixels;
  REQUIRE(raw.recv(topic));
  REQUIRE(raw.recv(envelope));
  REQUIRE(raw.recv(pixels));
  CHECK(sealedKeyId(envelope).has_value());
  REQUIRE(pixels.size() == 320 * 240 + kSealTag);
  std::map<unsigned char, int> counts;
  const auto* bytes = static_cast<const unsigned char*>(pixels.data());
  for (size_t i = 0; i < pixels.size(); ++i) ++counts[bytes[i]];
  int most = 0;
  for (const auto& [value, n] : counts) most = std::max(most, n);
  CHECK(most < static_cast<int>(pixels.size() / 100));  // about 1/256 each

  // Control: the listed client is answered; the others time out.
  ControlClient listed_control(context, server.control, 5s, keys.client(keys.listedSecret()));
  ControlClient unlisted_control(context, server.control, 2s, keys.client(keys.strangerSecret()));
  ControlClient plain_control(context, server.control, 2s);
  auto answered = listed_control.call(listCameras());
  REQUIRE(answered);
  CHECK(answered->list_cameras().cameras_size() == 1);
  auto refused = unlisted_control.call(listCameras());
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ControlErrc::kNoReply);
  auto ignored = plain_control.call(listCameras());
  REQUIRE_FALSE(ignored);
  CHECK(ignored.error().code == ControlErrc::kNoReply);
  // The same client is answered again after the refusals (positive control).
  CHECK(listed_control.call(listCameras()));
}

TEST_CASE("CURVE: picksight-cam and the vision app use their keys and LOCATE works",
          "[e2e][curve]") {
  Keys keys;
  std::vector<std::string> args = {"--source", "cam0=synthetic:width=640,height=480,parts=4,seed=3",
                                   "--mode", "trigger"};
  for (const auto& a : keys.serverArgs()) args.push_back(a);
  VideoServerProcess server(args);

  auto cam = [&](const std::vector<std::string>& key_args) {
    std::vector<std::string> argv = {binPath("picksight-cam"), "--control", server.control,
                                     "--timeout", "2000"};
    argv.insert(argv.end(), key_args.begin(), key_args.end());
    argv.push_back("list");
    return run(argv);
  };
  const auto listed =
      cam({"--curve-server-key", keys.serverPublic(), "--curve-key", keys.listedSecret()});
  CHECK(listed.exit_code == 0);
  CHECK_THAT(listed.out, Catch::Contains("cam0"));
  CHECK(cam({"--curve-server-key", keys.serverPublic(), "--curve-key", keys.strangerSecret()})
            .exit_code == 3);
  CHECK(cam({}).exit_code == 3);

  VisionProcess vision(
      server, "cam0", "",
      {"--curve-server-key", keys.serverPublic(), "--curve-key", keys.listedSecret()});
  auto robot = vision.connect();
  auto reply = robot.request("LOCATE 1", 10s);
  REQUIRE(reply);
  INFO("reply: " << *reply);
  // Parts found in a triggered frame: the frame came through CURVE.
  CHECK_FALSE(parseLocateReply(*reply).empty());
}

TEST_CASE("CURVE: a secret key others may read stops the server naming the file", "[e2e][curve]") {
  Keys keys;
  REQUIRE(::chmod(keys.serverSecret().c_str(), 0644) == 0);
  const std::string log = keys.dir.file("server.log");
  Subprocess server({"/bin/sh", "-c", "exec \"$@\" 2>\"$0\"", log,
                     binPath("picksight-video-server"), "--frames", "tcp://127.0.0.1:*",
                     "--control", "tcp://127.0.0.1:*", "--curve-secret-key", keys.serverSecret()});
  auto status = server.wait(10s);
  REQUIRE(status);
  CHECK(WIFEXITED(*status));
  CHECK(WEXITSTATUS(*status) != 0);
  CHECK_THAT(fileText(log), Catch::Contains(keys.serverSecret()) && Catch::Contains("chmod 600"));

  // A client's key file with the same fault: the vision app names it too.
  REQUIRE(::chmod(keys.listedSecret().c_str(), 0644) == 0);
  Subprocess vision({"/bin/sh", "-c", "exec \"$@\" 2>\"$0\"", keys.dir.file("vision.log"),
                     binPath("picksight-vision"), "--curve-server-key", keys.serverPublic(),
                     "--curve-key", keys.listedSecret()});
  auto vision_status = vision.wait(10s);
  REQUIRE(vision_status);
  CHECK(WEXITSTATUS(*vision_status) == 2);
  CHECK_THAT(fileText(keys.dir.file("vision.log")), Catch::Contains(keys.listedSecret()));
}
