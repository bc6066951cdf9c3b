// picksight-vision option parsing, with picksight::cli.
#include "picksight/app/app_options.hpp"

#include <set>

#include "picksight/cli/command_line.hpp"
#include "picksight/cli/config_file.hpp"
#include "picksight/common/allow_list.hpp"
#include "picksight/common/text.hpp"

namespace picksight::app {

using transport::loadClientKeys;

namespace {

// Values checked by the options' validators, converted after the parse.
struct RawOptions {
  std::string robot_port;
  std::string robot_allow;
  std::string robot_idle_timeout;
  std::string robot_per_address;
  std::string setup_port;
  std::string setup_bind = "127.0.0.1";
  std::string threshold;
  std::string polarity;
  std::string window;
  std::string min_area;
  std::string min_hole_area;
  std::string config_file;
  std::string modbus_port;
  std::string modbus_unit;
  std::string modbus_allow;
  std::string modbus_word_order;
  std::string curve_server_key;
  std::string curve_key;
  std::string filmstrip_dir;
  std::string filmstrip_entries;
  std::string filmstrip_mb;
  std::string filmstrip_failures;
  std::string filmstrip_failure_mb;
  std::string filmstrip_queue;
  std::string filmstrip_interval;
};

std::string checkRange(const std::string& v, long long low, long long high) {
  auto n = parseInt(v);
  if (n && *n >= low && *n <= high) return "";
  return "must be in [" + std::to_string(low) + ", " + std::to_string(high) + "], got '" + v + "'";
}

// The robot port's and the Modbus port's --*-allow: one syntax, one check.
std::string checkAllowList(const std::string& v) {
  auto list = AllowList::parse(v);
  return list ? std::string() : list.error().message;
}

std::string checkThreshold(const std::string& v) {
  if (v == "adaptive" || v == "otsu") return "";
  if (v.rfind("fixed:", 0) == 0) {
    auto level = parseInt(v.substr(6));
    if (level && *level >= 0 && *level <= 255) return "";
    return "fixed level must be in [0, 255], got '" + v + "'";
  }
  return "must be adaptive, otsu or fixed:LEVEL, got '" + v + "'";
}

// The filmstrip's directory and bounds (filmstrip.hpp).
void defineFilmstripOptions(cli::App& app, RawOptions& raw) {
  const filmstrip::FilmstripOptions defaults;
  const auto count = [](long long high) {
    return cli::checkValue([high](const std::string& v) { return checkRange(v, 1, high); });
  };
  app.addOption("--filmstrip-dir", raw.filmstrip_dir,
                "where the frames of recent LOCATE, WHY and PLC requests are kept "
                "(default DATA_DIR/filmstrip; 'none': no filmstrip)")
      ->typeName("DIR");
  app.addOption("--filmstrip-entries", raw.filmstrip_entries,
                "successful requests kept (default " + std::to_string(defaults.max_entries) + ")")
      ->typeName("N")
      ->check(count(1000000));
  app.addOption("--filmstrip-mb", raw.filmstrip_mb,
                "their megabytes on disk at most (default " +
                    std::to_string(defaults.max_bytes >> 20) + ")")
      ->typeName("MB")
      ->check(count(1000000));
  app.addOption("--filmstrip-failures", raw.filmstrip_failures,
                "failed requests (nothing found, an error) and WHYs kept (default " +
                    std::to_string(defaults.max_failures) + ")")
      ->typeName("N")
      ->check(count(1000000));
  app.addOption("--filmstrip-failure-mb", raw.filmstrip_failure_mb,
                "their megabytes on disk at most (default " +
                    std::to_string(defaults.max_failure_bytes >> 20) + ")")
      ->typeName("MB")
      ->check(count(1000000));
  app.addOption("--filmstrip-queue", raw.filmstrip_queue,
                "requests waiting to be written; beyond, successes are dropped first and "
                "counted (default " +
                    std::to_string(defaults.queue) + ")")
      ->typeName("N")
      ->check(count(4096));
  app.addOption("--filmstrip-success-ms", raw.filmstrip_interval,
                "a success is recorded only this long after the last one recorded (0: every "
                "one; failures always; default " +
                    std::to_string(defaults.success_interval.count()) + ")")
      ->typeName("MS")
      ->check(cli::checkValue([](const std::string& v) { return checkRange(v, 0, 86400000); }));
}

// Declares the options on `app`, bound to `o` and `raw`; parseAppArgs and
// appUsage share it, so the help lists exactly what is parsed. Long because
// it is one declaration per option, in the order --help lists them; it
// decides nothing.
void defineAppOptions(cli::App& app, AppOptions& o, RawOptions& raw) {
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--config", raw.config_file,
                "YAML file of options, each named as its flag without dashes "
                "(robot-port: 5600); options given here override it")
      ->typeName("FILE");
  app.addOption("--frames", o.frames_endpoint, "video server frame endpoint")
      ->typeName("ENDPOINT")
      ->showDefault();
  app.addOption("--control", o.control_endpoint, "video server control endpoint")
      ->typeName("ENDPOINT")
      ->showDefault();
  app.addOption("--camera", o.camera, "camera to watch")->typeName("NAME")->showDefault();
  app.addOption("--name", o.name, "this vision app's name, the results topic (default: the camera)")
      ->typeName("NAME")
      ->check(cli::checkValue([](const std::string& v) {
        return !v.empty() && v.size() <= 64 ? std::string() : "must be 1 to 64 characters";
      }));
  app.addOption("--results-bind", o.results_bind,
                "ZeroMQ endpoint the results stream is published on ('none': off)")
      ->typeName("ENDPOINT")
      ->showDefault();
  app.addOption("--robot-port", raw.robot_port,
                "TCP port for robot controllers (default 5600, 0 = any free)")
      ->typeName("PORT")
      ->check(cli::checkValue([](const std::string& v) { return checkRange(v, 0, 65535); }));
  app.addOption("--bind", o.robot.listen.bind_address,
                "address the robot port listens on (robots are other hosts: all interfaces)")
      ->typeName("ADDRESS")
      ->showDefault();
  app.addOption("--robot-allow", raw.robot_allow,
                "addresses or networks allowed to connect, e.g. '10.0.0.0/8 192.168.1.7' "
                "(default: any)")
      ->typeName("LIST")
      ->check(cli::checkValue(checkAllowList));
  app.addFlag("--robot-read-only", o.robot_read_only,
              "the robot port refuses requests that change models, calibration or camera");
  app.addOption("--robot-idle-timeout", raw.robot_idle_timeout,
                "seconds without a request before a connection is closed (default 60, 0 = never)")
      ->typeName("SECONDS")
      ->check(cli::checkValue([](const std::string& v) { return checkRange(v, 0, 86400); }));
  app.addOption("--robot-per-address", raw.robot_per_address,
                "connections allowed from one address (default 32 of 64, 0 = no own limit)")
      ->typeName("N")
      ->check(cli::checkValue([](const std::string& v) { return checkRange(v, 0, 64); }));
  app.addOption("--setup-port", raw.setup_port,
                "a second, full-access port for set-up (0 = any free; default: none)")
      ->typeName("PORT")
      ->check(cli::checkValue([](const std::string& v) { return checkRange(v, 0, 65535); }));
  app.addOption("--setup-bind", raw.setup_bind, "address the set-up port listens on")
      ->typeName("ADDRESS")
      ->showDefault();
  app.addOption("--data-dir", o.data_dir, "models and calibrations")
      ->typeName("DIR")
      ->showDefault();
  app.addOption("--threshold", raw.threshold, "binarization (default adaptive)")
      ->typeName("adaptive|otsu|fixed:LEVEL")
      ->check(cli::checkValue(checkThreshold));
  app.addOption("--polarity", raw.polarity,
                "dark parts on light background (default) or light on dark")
      ->typeName("dark|light")
      ->check(cli::checkValue([](const std::string& v) {
        return v == "dark" || v == "light" ? std::string()
                                           : "must be dark or light, got '" + v + "'";
      }));
  app.addOption("--window", raw.window, "adaptive illumination window, wider than the largest part")
      ->typeName("PIXELS")
      ->check(cli::checkValue([](const std::string& v) { return checkRange(v, 8, 16384); }));
  app.addOption("--min-area", raw.min_area,
                "smallest region that counts as a part (default: 50, or a twentieth of the "
                "smallest trained part when that is more)")
      ->typeName("PIXELS")
      ->check(cli::checkValue([](const std::string& v) {
        auto m = parseDouble(v);
        return m && *m >= 1 ? std::string() : "must be a number >= 1, got '" + v + "'";
      }));
  app.addOption("--min-hole-area", raw.min_hole_area,
                "smallest hole (sensor pixels) counted in a part (default 0: every hole)")
      ->typeName("PIXELS")
      ->check(cli::checkValue([](const std::string& v) {
        auto m = parseDouble(v);
        return m && *m >= 0 && *m <= 1e9 ? std::string()
                                         : "must be a number in [0, 1e9], got '" + v + "'";
      }));
  app.addOption("--modbus-port", raw.modbus_port,
                "TCP port of the PLC (Modbus TCP) server; absent = no PLC port, 0 = any free")
      ->typeName("PORT")
      ->check(cli::checkValue([](const std::string& v) { return checkRange(v, 0, 65535); }));
  app.addOption("--modbus-bind", o.plc.server.listen.bind_address,
                "address the Modbus port listens on")
      ->typeName("ADDRESS")
      ->showDefault();
  app.addOption("--modbus-unit", raw.modbus_unit, "Modbus unit id answered (default 1)")
      ->typeName("1-247")
      ->check(cli::checkValue([](const std::string& v) { return checkRange(v, 1, 247); }));
  app.addOption("--modbus-allow", raw.modbus_allow,
                "PLCs that may connect: addresses or networks (default any)")
      ->typeName("LIST")
      ->check(cli::checkValue(checkAllowList));
  app.addOption("--modbus-word-order", raw.modbus_word_order,
                "32-bit values: high word first (ABCD, default) or low word first (CDAB)")
      ->typeName("ABCD|CDAB")
      ->check(cli::checkValue([](const std::string& v) {
        return plc::parseWordOrder(v) ? std::string() : "must be ABCD or CDAB, got '" + v + "'";
      }));
  defineFilmstripOptions(app, raw);
  cli::Option* server_key =
      app.addOption("--curve-server-key", raw.curve_server_key,
                    "talk CURVE to the video server: its public NAME.key (docs/SECURITY.md)")
          ->typeName("FILE");
  app.addOption("--curve-key", raw.curve_key,
                "this client's NAME.key_secret, for a server with an allow-list "
                "(default: a fresh key pair)")
      ->typeName("FILE")
      ->needs(server_key);
  app.footer(
      "On start it prints 'robot <port>', 'setup <port>' (with --setup-port), 'modbus <port>' "
      "(with --modbus-port), 'results <endpoint>' (unless --results-bind none) and 'ready' on "
      "stdout.");
}

cli::App visionApp() {
  return cli::App("Subscribes to one camera of a video server and answers robot controllers.",
                  "picksight-vision");
}

}  // namespace

std::string appUsage() { return cli::toolUsage(visionApp, defineAppOptions); }

namespace {

Result<AppOptions> finishOptions(AppOptions o, RawOptions& raw) {
  // The validators accepted these: the conversions cannot fail.
  if (!raw.robot_port.empty())
    o.robot.listen.port = static_cast<uint16_t>(*parseInt(raw.robot_port));
  if (!raw.robot_allow.empty()) o.robot.listen.allow = *AllowList::parse(raw.robot_allow);
  if (!raw.robot_idle_timeout.empty())
    o.robot.listen.idle_timeout = std::chrono::seconds(*parseInt(raw.robot_idle_timeout));
  if (!raw.robot_per_address.empty())
    o.robot.listen.max_per_address = static_cast<size_t>(*parseInt(raw.robot_per_address));
  if (!raw.setup_port.empty()) {
    o.setup = o.robot;
    o.setup->listen.port = static_cast<uint16_t>(*parseInt(raw.setup_port));
    o.setup->listen.bind_address = raw.setup_bind;
    o.setup->label = "setup";
  }
  // Keys of vision_settings.hpp: given here, they win over vision.json.
  if (!raw.threshold.empty()) o.vision_settings_given.emplace_back("threshold");
  if (raw.threshold.rfind("fixed:", 0) == 0) o.vision_settings_given.emplace_back("level");
  if (!raw.polarity.empty()) o.vision_settings_given.emplace_back("polarity");
  if (!raw.window.empty()) o.vision_settings_given.emplace_back("window");
  if (!raw.min_area.empty()) o.vision_settings_given.emplace_back("min_area");
  if (!raw.min_hole_area.empty()) o.vision_settings_given.emplace_back("min_hole_area");
  if (raw.threshold == "adaptive") {
    o.vision.binarize.method = vision::ThresholdMethod::kAdaptive;
  } else if (raw.threshold == "otsu") {
    o.vision.binarize.method = vision::ThresholdMethod::kOtsu;
  } else if (!raw.threshold.empty()) {
    o.vision.binarize.method = vision::ThresholdMethod::kFixed;
    o.vision.binarize.fixed_threshold = static_cast<int>(*parseInt(raw.threshold.substr(6)));
  }
  if (!raw.polarity.empty()) {
    o.vision.binarize.polarity =
        raw.polarity == "dark" ? vision::Polarity::kDarkOnLight : vision::Polarity::kLightOnDark;
  }
  if (!raw.window.empty())
    o.vision.binarize.adaptive_window = static_cast<int>(*parseInt(raw.window));
  if (!raw.min_area.empty()) {
    o.vision.regions.min_area = *parseDouble(raw.min_area);
    o.vision.min_area_follows_models = false;
  }
  if (!raw.min_hole_area.empty()) o.vision.regions.min_hole_area = *parseDouble(raw.min_hole_area);
  o.plc.enabled = !raw.modbus_port.empty();
  if (o.plc.enabled) o.plc.server.listen.port = static_cast<uint16_t>(*parseInt(raw.modbus_port));
  if (!raw.modbus_unit.empty())
    o.plc.device.unit_id = static_cast<uint8_t>(*parseInt(raw.modbus_unit));
  if (!raw.modbus_allow.empty()) o.plc.server.listen.allow = *AllowList::parse(raw.modbus_allow);
  if (!raw.modbus_word_order.empty())
    o.plc.device.word_order = *plc::parseWordOrder(raw.modbus_word_order);
  if (raw.filmstrip_dir != "none")
    o.filmstrip.dir = raw.filmstrip_dir.empty() ? o.data_dir + "/filmstrip" : raw.filmstrip_dir;
  if (!raw.filmstrip_entries.empty())
    o.filmstrip.max_entries = static_cast<size_t>(*parseInt(raw.filmstrip_entries));
  if (!raw.filmstrip_mb.empty())
    o.filmstrip.max_bytes = static_cast<uint64_t>(*parseInt(raw.filmstrip_mb)) << 20;
  if (!raw.filmstrip_failures.empty())
    o.filmstrip.max_failures = static_cast<size_t>(*parseInt(raw.filmstrip_failures));
  if (!raw.filmstrip_failure_mb.empty())
    o.filmstrip.max_failure_bytes = static_cast<uint64_t>(*parseInt(raw.filmstrip_failure_mb))
                                    << 20;
  if (!raw.filmstrip_queue.empty())
    o.filmstrip.queue = static_cast<size_t>(*parseInt(raw.filmstrip_queue));
  if (!raw.filmstrip_interval.empty())
    o.filmstrip.success_interval = std::chrono::milliseconds(*parseInt(raw.filmstrip_interval));
  if (!raw.curve_server_key.empty()) {
    auto keys = loadClientKeys(raw.curve_key, raw.curve_server_key);
    if (!keys) return keys.error();
    o.curve = std::move(*keys);
  }
  return o;
}

}  // namespace

Result<AppOptions> parseAppArgs(const std::vector<std::string>& args, bool* help) {
  return cli::parseToolOptions<AppOptions, RawOptions>(args, help, visionApp, defineAppOptions,
                                                       finishOptions);
}

}  // namespace picksight::app
