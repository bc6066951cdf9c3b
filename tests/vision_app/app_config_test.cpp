// picksight-vision --config: a YAML map of options named as their flags,
// overridden by the command line; a bad key or value names the file and key.
#include <catch2/catch.hpp>

#include "picksight/app/app_options.hpp"
#include "picksight/cli/command_line.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using picksight::test::TempDir;

namespace {

Result<app::AppOptions> parse(const std::vector<std::string>& args) {
  bool help = false;
  return app::parseAppArgs(args, &help);
}

// The error of parsing `yaml` as the only option; REQUIREs that it failed.
std::string configError(const std::string& yaml) {
  TempDir dir;
  const std::string path = dir.write("cell.yaml", yaml);
  auto parsed = parse({"--config", path});
  REQUIRE_FALSE(parsed);
  CHECK(parsed.error().code == cli::CommandLineErrc::kBadOption);
  // Every message names the file, so a service log points at it.
  CHECK(parsed.error().message.find(path) != std::string::npos);
  return parsed.error().message;
}

}  // namespace

TEST_CASE("Config file keys are the options without dashes", "[vision_app][config]") {
  TempDir dir;
  const std::string path = dir.write("cell.yaml",
                                     "frames: tcp://10.0.0.2:5555\n"
                                     "control: tcp://10.0.0.2:5556\n"
                                     "camera: line1\n"
                                     "robot-port: 7000\n"
                                     "bind: 127.0.0.1\n"
                                     "data-dir: /srv/cell\n"
                                     "threshold: fixed:100\n"
                                     "polarity: light\n"
                                     "window: 64\n"
                                     "min-area: 80\n");
  auto o = parse({"--config", path});
  REQUIRE(o);
  CHECK(o->frames_endpoint == "tcp://10.0.0.2:5555");
  CHECK(o->control_endpoint == "tcp://10.0.0.2:5556");
  CHECK(o->camera == "line1");
  CHECK(o->robot.listen.port == 7000);
  CHECK(o->robot.listen.bind_address == "127.0.0.1");
  CHECK(o->data_dir == "/srv/cell");
  CHECK(o->vision.binarize.method == vision::ThresholdMethod::kFixed);
  CHECK(o->vision.binarize.fixed_threshold == 100);
  CHECK(o->vision.binarize.polarity == vision::Polarity::kLightOnDark);
  CHECK(o->vision.binarize.adaptive_window == 64);
  CHECK(o->vision.regions.min_area == 80);
}

TEST_CASE("Command line options override the config file", "[vision_app][config]") {
  TempDir dir;
  const std::string path = dir.write("cell.yaml", "robot-port: 7000\ncamera: line1\n");
  // Before or after --config: the command line wins either way.
  auto before = parse({"--robot-port", "7001", "--config", path});
  REQUIRE(before);
  CHECK(before->robot.listen.port == 7001);
  CHECK(before->camera == "line1");
  auto after = parse({"--config", path, "--robot-port", "0"});
  REQUIRE(after);
  CHECK(after->robot.listen.port == 0);
}

TEST_CASE("An empty config file changes nothing", "[vision_app][config]") {
  TempDir dir;
  auto o = parse({"--config", dir.write("cell.yaml", "# nothing yet\n")});
  REQUIRE(o);
  CHECK(o->camera == app::AppOptions().camera);
  CHECK(o->robot.listen.port == app::AppOptions().robot.listen.port);
}

TEST_CASE("The packaged example config parses", "[vision_app][config]") {
  const std::string path =
      std::string(PICKSIGHT_TEST_DATA_DIR) + "/../../deploy/etc/picksight/vision/cam0.yaml";
  auto o = parse({"--config", path});
  REQUIRE(o);
  CHECK(o->camera == "cam0");
  CHECK(o->robot.listen.port == 5600);
  CHECK(o->frames_endpoint == "tcp://127.0.0.1:5555");
}

TEST_CASE("A config key that is no option is named", "[vision_app][config]") {
  CHECK_THAT(configError("camera: cam0\nspeed: 3\n"), Catch::Contains("speed: unknown key"));
  // The file cannot include another, ask for help or use dashed names.
  CHECK_THAT(configError("config: other.yaml\n"), Catch::Contains("config: unknown key"));
  CHECK_THAT(configError("help: true\n"), Catch::Contains("help: unknown key"));
  CHECK_THAT(configError("--camera: cam0\n"), Catch::Contains("--camera: unknown key"));
}

TEST_CASE("A bad config value is named by its key", "[vision_app][config]") {
  const std::string port = configError("robot-port: 70000\n");
  CHECK_THAT(port, Catch::Contains(": robot-port: must be in [0, 65535], got '70000'"));
  CHECK_THAT(configError("threshold: bright\n"), Catch::Contains(": threshold: must be"));
  CHECK_THAT(configError("camera: [cam0, cam1]\n"),
             Catch::Contains("camera: takes one value, not a list"));
  CHECK_THAT(configError("camera: {name: cam0}\n"), Catch::Contains("camera: must be a value"));
  CHECK_THAT(configError("camera: cam0\ncamera: cam1\n"), Catch::Contains("camera: given twice"));
}

TEST_CASE("A config file that is not a map of options is refused", "[vision_app][config]") {
  CHECK_THAT(configError("- camera\n- cam0\n"), Catch::Contains("must be a map"));
  CHECK_THAT(configError("camera: [unclosed\n"), Catch::Contains("--config"));
  auto missing = parse({"--config", "/nonexistent/picksight/cell.yaml"});
  REQUIRE_FALSE(missing);
  CHECK_THAT(missing.error().message, Catch::Contains("/nonexistent/picksight/cell.yaml"));
}

TEST_CASE("The results stream's endpoint and topic are options and config keys",
          "[vision_app][config]") {
  auto defaults = parse({});
  REQUIRE(defaults);
  CHECK(defaults->results_bind == "tcp://127.0.0.1:*");
  CHECK(defaults->name.empty());  // the camera's name
  TempDir dir;
  const std::string path =
      dir.write("cell.yaml", "results-bind: tcp://127.0.0.1:5610\nname: line1-left\n");
  auto o = parse({"--config", path});
  REQUIRE(o);
  CHECK(o->results_bind == "tcp://127.0.0.1:5610");
  CHECK(o->name == "line1-left");
  auto off = parse({"--results-bind", "none"});
  REQUIRE(off);
  CHECK(off->results_bind == "none");
  CHECK(configError("name: ''\n").find("name") != std::string::npos);
}
