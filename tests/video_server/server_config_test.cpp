// Pins the video server's configuration: command-line defaults and flags,
// and YAML files whose errors name the file and the key path.
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "temp_dir.hpp"

#include "picksight/video_server/server_config.hpp"

namespace fs = std::filesystem;
using picksight::video::AcquisitionMode;
using picksight::video::loadServerConfig;
using picksight::video::OutputFormat;
using picksight::video::parseServerArgs;

namespace {

using picksight::test::TempDir;

// The error message of a configuration that must be rejected.
std::string argsError(const std::vector<std::string>& args) {
  auto config = parseServerArgs(args, nullptr);
  return config ? "accepted" : config.error().message;
}

std::string yamlError(const std::string& yaml) {
  TempDir dir;
  const std::string path = dir.write("server.yaml", yaml);
  auto config = loadServerConfig(path);
  if (config) return "accepted";
  CHECK_THAT(config.error().message, Catch::Contains(path));
  return config.error().message;
}

const char* const kTwoCameras = R"(
frames: tcp://127.0.0.1:7001
control: tcp://127.0.0.1:7002
cameras:
  - name: top
    source: "synthetic:width=320,height=240"
    mode: trigger
    fps: 25
    no_frame_timeout: 1.5
  - name: side
    source: file:/data/side.png
    format: bgr8
    roi: [10, 20, 300, 200]
    size: [150, 100]
  - name: scaled
    source: "synthetic:"
    scale: 0.5
)";

}  // namespace

TEST_CASE("parseServerArgs defaults to one free-running synthetic camera", "[video_server]") {
  bool help = true;
  auto config = parseServerArgs({}, &help);
  REQUIRE(config);
  CHECK_FALSE(help);
  CHECK(config->frames_endpoint == "tcp://*:5555");
  CHECK(config->control_endpoint == "tcp://*:5556");
  REQUIRE(config->cameras.size() == 1);
  const auto& cam = config->cameras[0];
  CHECK(cam.name == "cam0");
  CHECK(cam.uri == "synthetic:");
  CHECK(cam.mode == AcquisitionMode::kFreeRun);
  CHECK(cam.fps == 10);
  CHECK(cam.output.roi.empty());
  CHECK(cam.output.format == OutputFormat::kMono8);
}

TEST_CASE("parseServerArgs --help sets the flag", "[video_server]") {
  bool help = false;
  auto config = parseServerArgs({"--help"}, &help);
  REQUIRE(config);
  CHECK(help);
  CHECK_THAT(picksight::video::serverUsage(), Catch::Contains("--source"));
}

TEST_CASE("parseServerArgs --source NAME=URI repeated, with --mode and --fps", "[video_server]") {
  auto config = parseServerArgs({"--source", "top=synthetic:parts=3", "--mode", "trigger",
                                 "--source", "side=file:/data/a=b.png", "--fps", "25.5", "--frames",
                                 "tcp://127.0.0.1:*", "--control", "ipc:///tmp/c"},
                                nullptr);
  REQUIRE(config);
  REQUIRE(config->cameras.size() == 2);
  CHECK(config->cameras[0].name == "top");
  CHECK(config->cameras[0].uri == "synthetic:parts=3");
  CHECK(config->cameras[1].name == "side");
  CHECK(config->cameras[1].uri == "file:/data/a=b.png");
  for (const auto& c : config->cameras) {
    CHECK(c.mode == AcquisitionMode::kTrigger);
    CHECK(c.fps == 25.5);
  }
  CHECK(config->frames_endpoint == "tcp://127.0.0.1:*");
  CHECK(config->control_endpoint == "ipc:///tmp/c");
}

TEST_CASE("parseServerArgs --mode and --fps apply to the default camera", "[video_server]") {
  auto config = parseServerArgs({"--mode", "trigger", "--fps", "30"}, nullptr);
  REQUIRE(config);
  REQUIRE(config->cameras.size() == 1);
  CHECK(config->cameras[0].mode == AcquisitionMode::kTrigger);
  CHECK(config->cameras[0].fps == 30);
}

TEST_CASE("parseServerArgs errors name the option", "[video_server]") {
  CHECK_THAT(argsError({"--fps", "fast"}), Catch::StartsWith("--fps") && Catch::Contains("'fast'"));
  CHECK_THAT(argsError({"--fps", "0"}), Catch::StartsWith("--fps"));
  CHECK_THAT(argsError({"--fps", "1e6"}), Catch::StartsWith("--fps"));
  CHECK_THAT(argsError({"--fps", "12,5"}), Catch::StartsWith("--fps"));
  CHECK_THAT(argsError({"--mode", "continuous"}), Catch::StartsWith("--mode"));
  CHECK_THAT(argsError({"--source", "synthetic:"}), Catch::StartsWith("--source"));
  CHECK_THAT(argsError({"--source", "=synthetic:"}), Catch::StartsWith("--source"));
  CHECK_THAT(argsError({"--source", "cam="}), Catch::StartsWith("--source"));
  CHECK_THAT(argsError({"--fps"}), Catch::Contains("--fps"));
  CHECK_THAT(argsError({"--speed", "3"}), Catch::Contains("--speed"));
  CHECK_THAT(argsError({"--source", "a=synthetic:", "--source", "a=file:/x.png"}),
             Catch::Contains("'a'") && Catch::Contains("twice"));
}

TEST_CASE("loadServerConfig reads endpoints and cameras with their output", "[video_server]") {
  TempDir dir;
  auto config = loadServerConfig(dir.write("server.yaml", kTwoCameras));
  REQUIRE(config);
  CHECK(config->frames_endpoint == "tcp://127.0.0.1:7001");
  CHECK(config->control_endpoint == "tcp://127.0.0.1:7002");
  REQUIRE(config->cameras.size() == 3);
  const auto& top = config->cameras[0];
  CHECK(top.name == "top");
  CHECK(top.uri == "synthetic:width=320,height=240");
  CHECK(top.mode == AcquisitionMode::kTrigger);
  CHECK(top.fps == 25);
  CHECK(top.no_frame_timeout == std::chrono::milliseconds(1500));
  const auto& side = config->cameras[1];
  CHECK(side.no_frame_timeout == std::chrono::milliseconds(5000));
  // Only what was written is asked of a camera: its own rate and trigger stay.
  CHECK(top.mode_asked);
  CHECK(top.fps_asked);
  CHECK_FALSE(side.mode_asked);
  CHECK_FALSE(side.fps_asked);
  CHECK(side.mode == AcquisitionMode::kFreeRun);
  CHECK(side.output.format == OutputFormat::kBgr8);
  CHECK(side.output.roi == cv::Rect(10, 20, 300, 200));
  CHECK(side.output.size == cv::Size(150, 100));
  CHECK(config->cameras[2].output.scale == 0.5);
}

TEST_CASE("parseServerArgs --config loads the file, and --frames overrides it", "[video_server]") {
  TempDir dir;
  const std::string path = dir.write("server.yaml", kTwoCameras);
  auto config = parseServerArgs({"--config", path, "--frames", "tcp://127.0.0.1:*"}, nullptr);
  REQUIRE(config);
  CHECK(config->frames_endpoint == "tcp://127.0.0.1:*");
  CHECK(config->control_endpoint == "tcp://127.0.0.1:7002");
  CHECK(config->cameras.size() == 3);
  CHECK_THAT(argsError({"--config", path, "--source", "top=synthetic:"}), Catch::Contains("'top'"));
}

TEST_CASE("loadServerConfig errors name the key path", "[video_server]") {
  CHECK_THAT(yamlError("cameraz: []\n"), Catch::Contains("cameraz"));
  CHECK_THAT(yamlError("cameras:\n"
                       "  - {name: a, source: 'synthetic:'}\n"
                       "  - {name: b, source: 'synthetic:', fsp: 10}\n"),
             Catch::Contains("cameras[1].fsp"));
  CHECK_THAT(yamlError("cameras:\n"
                       "  - {name: a, source: 'synthetic:'}\n"
                       "  - {name: b, source: 'synthetic:', fps: fast}\n"),
             Catch::Contains("cameras[1].fps"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', fps: 0}\n"),
             Catch::Contains("cameras[0].fps"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', no_frame_timeout: 0}\n"),
             Catch::Contains("cameras[0].no_frame_timeout"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', no_frame_timeout: x}\n"),
             Catch::Contains("cameras[0].no_frame_timeout"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', mode: burst}\n"),
             Catch::Contains("cameras[0].mode"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', format: rgb565}\n"),
             Catch::Contains("cameras[0].format"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', roi: [1, 2, 3]}\n"),
             Catch::Contains("cameras[0].roi"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', roi: [1, 2, -3, 4]}\n"),
             Catch::Contains("cameras[0].roi"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', roi: [a, b, c, d]}\n"),
             Catch::Contains("cameras[0].roi"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', roi: 12}\n"),
             Catch::Contains("cameras[0].roi"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', size: [100]}\n"),
             Catch::Contains("cameras[0].size"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', size: [100, 0]}\n"),
             Catch::Contains("cameras[0]") && Catch::Contains("size"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'synthetic:', scale: 0}\n"),
             Catch::Contains("cameras[0].scale"));
  CHECK_THAT(yamlError("cameras:\n"
                       "  - {name: a, source: 'synthetic:'}\n"
                       "  - {name: b}\n"),
             Catch::Contains("cameras[1].source"));
  CHECK_THAT(yamlError("cameras:\n  - {source: 'synthetic:'}\n"),
             Catch::Contains("cameras[0].name"));
  CHECK_THAT(yamlError("cameras:\n  - just a string\n"), Catch::Contains("cameras[0]"));
  CHECK_THAT(yamlError("cameras: {name: a}\n"), Catch::Contains("cameras"));
  CHECK_THAT(yamlError("cameras:\n"
                       "  - {name: twin, source: 'synthetic:'}\n"
                       "  - {name: twin, source: 'file:/x.png'}\n"),
             Catch::Contains("'twin'") && Catch::Contains("twice"));
}

TEST_CASE("loadServerConfig reads a hardware trigger's line, edge and timeout", "[video_server]") {
  TempDir dir;
  const std::string path = dir.write("server.yaml",
                                     "cameras:\n"
                                     "  - name: gige\n"
                                     "    source: 'aravis:Basler-123'\n"
                                     "    mode: hardware\n"
                                     "    trigger_line: Line2\n"
                                     "    trigger_activation: FallingEdge\n"
                                     "    trigger_timeout: 2.5\n"
                                     "  - {name: plain, source: 'aravis:', mode: hardware}\n");
  auto config = loadServerConfig(path);
  REQUIRE(config);
  const auto& gige = config->cameras[0];
  CHECK(gige.mode == AcquisitionMode::kHardwareTrigger);
  CHECK(gige.mode_asked);
  CHECK(gige.hardware.input.line == "Line2");
  CHECK(gige.hardware.input.activation == "FallingEdge");
  CHECK(gige.hardware.timeout == std::chrono::milliseconds(2500));
  // The defaults: Line1, the camera's own edge, 10 s.
  const auto& plain = config->cameras[1];
  CHECK(plain.hardware.input.line == "Line1");
  CHECK(plain.hardware.input.activation.empty());
  CHECK(plain.hardware.timeout == std::chrono::milliseconds(10000));

  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'aravis:', trigger_activation: up}\n"),
             Catch::Contains("cameras[0].trigger_activation"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'aravis:', trigger_timeout: 0}\n"),
             Catch::Contains("cameras[0].trigger_timeout"));
  CHECK_THAT(yamlError("cameras:\n  - {name: a, source: 'aravis:', trigger_line: ''}\n"),
             Catch::Contains("cameras[0].trigger_line"));
}

TEST_CASE("loadServerConfig rejects unreadable or malformed files naming the file",
          "[video_server]") {
  TempDir dir;
  const std::string missing = dir.write("placeholder", "") + ".absent.yaml";
  auto config = loadServerConfig(missing);
  REQUIRE_FALSE(config);
  CHECK_THAT(config.error().message, Catch::Contains(missing));
  CHECK_THAT(yamlError("cameras: [unclosed\n"), Catch::Contains("server.yaml"));
  CHECK_THAT(yamlError("- a list\n- not a map\n"), Catch::Contains("map"));
  // Keys that are not text must be an error value too, never an exception.
  CHECK_THAT(yamlError("? [a, b]\n: 1\n"), Catch::Contains("server.yaml"));
  CHECK_THAT(yamlError("cameras:\n  - {? [x]: 1, name: a, source: 'synthetic:'}\n"),
             Catch::Contains("cameras[0]"));
}

TEST_CASE("CURVE key files come from the curve map or the flags which override it",
          "[video_server]") {
  TempDir dir;
  const std::string path = dir.write("server.yaml",
                                     "curve:\n  secret_key: /etc/keys/server.key_secret\n"
                                     "  clients: /etc/keys/clients\n");
  auto config = loadServerConfig(path);
  REQUIRE(config);
  CHECK(config->curve_secret_key == "/etc/keys/server.key_secret");
  CHECK(config->curve_allow_list == "/etc/keys/clients");
  auto flags = parseServerArgs({"--config", path, "--curve-clients", "/tmp/clients"}, nullptr);
  REQUIRE(flags);
  CHECK(flags->curve_secret_key == "/etc/keys/server.key_secret");
  CHECK(flags->curve_allow_list == "/tmp/clients");
  auto plain = parseServerArgs({}, nullptr);
  REQUIRE(plain);
  CHECK(plain->curve_secret_key.empty());
  CHECK_THAT(yamlError("curve:\n  secret: x\n"), Catch::Contains("curve.secret: unknown key"));
  CHECK_THAT(yamlError("curve:\n  clients: [a, b]\n"),
             Catch::Contains("curve.clients: must be a file name"));
  CHECK_THAT(yamlError("curve: on\n"), Catch::Contains("curve: must be a map"));
}
