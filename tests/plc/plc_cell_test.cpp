// The PLC port of a real cell: picksight-video-server (synthetic camera) and
// picksight-vision with --modbus-port, driven by libmodbus's client through
// the handshake; the poses are compared with the robot port's LOCATE.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>

#include "cell_fixture.hpp"
#include "modbus_client.hpp"
#include "picksight/common/text.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::plc;
using namespace picksight::tool_support;
using picksight::plc::test::ModbusClient;
using namespace std::chrono_literals;

namespace {
// picksight-vision with its PLC port on a free port.
struct PlcVision {
  explicit PlcVision(const VideoServerProcess& server) {
    char dir[] = "/tmp/picksight-plc-XXXXXX";
    REQUIRE(::mkdtemp(dir) != nullptr);
    data_dir = dir;
    process = std::make_unique<Subprocess>(std::vector<std::string>{
        binPath("picksight-vision"), "--frames", server.frames, "--control", server.control,
        "--robot-port", "0", "--bind", "127.0.0.1", "--data-dir", data_dir, "--modbus-port", "0",
        "--modbus-bind", "127.0.0.1", "--modbus-allow", "127.0.0.1"});
    const auto robot = process->waitForLine("robot ", 10s);
    REQUIRE(robot);
    robot_port = static_cast<uint16_t>(*parseInt(*robot));
    const auto modbus = process->waitForLine("modbus ", 10s);
    REQUIRE(modbus);
    modbus_port = static_cast<uint16_t>(*parseInt(*modbus));
    REQUIRE(process->waitForLine("ready", 10s));
  }
  ~PlcVision() {
    process.reset();
    std::error_code ignored;
    std::filesystem::remove_all(data_dir, ignored);
  }
  LineClient robot() const {
    auto c = LineClient::connect("127.0.0.1", robot_port, 5s);
    REQUIRE(c);
    return std::move(*c);
  }
  std::unique_ptr<Subprocess> process;
  std::string data_dir;
  uint16_t robot_port = 0;
  uint16_t modbus_port = 0;
};

uint64_t frameOf(LineClient& robot) {
  const auto reply = robot.request("FRAME", 5s);
  REQUIRE(reply);
  const auto words = splitFields(*reply, " ");
  REQUIRE(words.size() >= 3);
  const auto sequence = parseInt(words[2]);
  REQUIRE(sequence);
  return static_cast<uint64_t>(*sequence);
}
}  // namespace

TEST_CASE("a PLC triggers a LOCATE and reads the robot port's poses", "[plc][e2e]") {
  // One part, a still scene without noise: every frame is the same image.
  VideoServerProcess server({"--source",
                             "cam0=synthetic:width=640,height=480,parts=1,types=l_shape,seed=3,"
                             "noise=0",
                             "--mode", "trigger"});
  PlcVision vision(server);
  auto robot = vision.robot();
  ModbusClient plc(vision.modbus_port);
  CHECK(plc.read(reg::kCalibration) == kFrameVisionPixels);
  CHECK((plc.status() & kStatusCalibrated) == 0);

  auto reply = robot.request("LEARN 1 bracket", 10s);
  REQUIRE(reply);
  REQUIRE(reply->rfind("OK 1 bracket ", 0) == 0);

  // A type with no model while another exists: the robot port's ERROR 32.
  uint16_t status = plc.trigger(2);
  CHECK((status & kStatusError) != 0);
  CHECK(plc.read(reg::kErrorCode) == 32);
  plc.write(reg::kControl, kControlClearError);
  plc.write(reg::kControl, 0);

  for (const uint16_t type : {uint16_t{1}, kAllTypes}) {
    status = plc.trigger(type);
    INFO("type " << type << " status " << status << " error " << plc.read(reg::kErrorCode));
    REQUIRE(status == kStatusResultsValid);
    const uint32_t sequence = getU32(plc.read(reg::kFrameSequence, 2).data(), WordOrder::kABCD);
    CHECK(sequence == frameOf(robot));  // the frame the trigger used
    CHECK(plc.read(reg::kResultFrame) == kFrameVisionPixels);
    const auto parts = plc.parts();
    plc.acknowledge();
    REQUIRE(parts.size() == 1);
    CHECK(parts[0].type == 1);
    CHECK(parts[0].score > 0.5f);

    reply = robot.request("LOCATE 1", 10s);
    REQUIRE(reply);
    const auto poses = parseLocateReply(*reply);
    REQUIRE(poses.size() == 1);
    INFO("LOCATE " << *reply << " / PLC " << parts[0].x << " " << parts[0].y << " " << parts[0].rz);
    // The text protocol prints 3 decimals; the registers hold float32.
    CHECK(std::abs(parts[0].x - poses[0].x) < 0.002);
    CHECK(std::abs(parts[0].y - poses[0].y) < 0.002);
    CHECK(std::abs(parts[0].rz - poses[0].rz) < 0.002);
  }

  // The camera goes away: the trigger fails with the robot port's camera code.
  server.process.reset();
  status = plc.trigger(1);
  CHECK((status & kStatusError) != 0);
  const uint16_t code = plc.read(reg::kErrorCode);
  CHECK((code == 20 || code == 21));
  // The robot port still answers.
  CHECK(*robot.request("PING", 5s) == "OK");
}
