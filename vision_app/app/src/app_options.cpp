// picksight-vision option parsing, with CLI11.
#include "picksight/vision_app/app_options.hpp"

#include <CLI/CLI.hpp>

#include "picksight/common/command_line.hpp"
#include "picksight/common/text.hpp"

namespace picksight::app {

namespace {

// Values checked by the options' validators, converted after the parse.
struct RawOptions {
  std::string robot_port;
  std::string threshold;
  std::string polarity;
  std::string window;
  std::string min_area;
  std::string curve_server_key;
  std::string curve_key;
};

std::string checkRange(const std::string& v, long long low, long long high) {
  auto n = parseInt(v);
  if (n && *n >= low && *n <= high) return "";
  return "must be in [" + std::to_string(low) + ", " + std::to_string(high) + "], got '" + v + "'";
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

// Declares the options on `app`, bound to `o` and `raw`; parseAppArgs and
// appUsage share it, so the help lists exactly what is parsed.
void defineAppOptions(CLI::App& app, AppOptions& o, RawOptions& raw) {
  app.set_help_flag("-h,--help", "print this help");
  app.add_option("--frames", o.frames_endpoint, "video server frame endpoint")
      ->type_name("ENDPOINT")
      ->capture_default_str();
  app.add_option("--control", o.control_endpoint, "video server control endpoint")
      ->type_name("ENDPOINT")
      ->capture_default_str();
  app.add_option("--camera", o.camera, "camera to watch")->type_name("NAME")->capture_default_str();
  app.add_option("--robot-port", raw.robot_port,
                 "TCP port for robot controllers (default 5600, 0 = any free)")
      ->type_name("PORT")
      ->check(checkValue([](const std::string& v) { return checkRange(v, 0, 65535); }));
  app.add_option("--bind", o.robot.bind_address, "address the robot port listens on")
      ->type_name("ADDRESS")
      ->capture_default_str();
  app.add_option("--data-dir", o.data_dir, "models and calibrations")
      ->type_name("DIR")
      ->capture_default_str();
  app.add_option("--threshold", raw.threshold, "binarization (default adaptive)")
      ->type_name("adaptive|otsu|fixed:LEVEL")
      ->check(checkValue(checkThreshold));
  app.add_option("--polarity", raw.polarity,
                 "dark parts on light background (default) or light on dark")
      ->type_name("dark|light")
      ->check(checkValue([](const std::string& v) {
        return v == "dark" || v == "light" ? std::string()
                                           : "must be dark or light, got '" + v + "'";
      }));
  app.add_option("--window", raw.window,
                 "adaptive illumination window, wider than the largest part")
      ->type_name("PIXELS")
      ->check(checkValue([](const std::string& v) { return checkRange(v, 8, 16384); }));
  app.add_option("--min-area", raw.min_area, "smallest region that counts as a part (default 50)")
      ->type_name("PIXELS")
      ->check(checkValue([](const std::string& v) {
        auto m = parseDouble(v);
        return m && *m >= 1 ? std::string() : "must be a number >= 1, got '" + v + "'";
      }));
  CLI::Option* server_key =
      app.add_option("--curve-server-key", raw.curve_server_key,
                     "talk CURVE to the video server: its public NAME.key (docs/SECURITY.md)")
          ->type_name("FILE");
  app.add_option("--curve-key", raw.curve_key,
                 "this client's NAME.key_secret, for a server with an allow-list "
                 "(default: a fresh key pair)")
      ->type_name("FILE")
      ->needs(server_key);
  app.footer("On start it prints 'robot <port>' and 'ready' on stdout.");
}

CLI::App visionApp() {
  return CLI::App("Subscribes to one camera of a video server and answers robot controllers.",
                  "picksight-vision");
}

}  // namespace

std::string appUsage() {
  CLI::App app = visionApp();
  AppOptions options;
  RawOptions raw;
  defineAppOptions(app, options, raw);
  return app.help();
}

Result<AppOptions> parseAppArgs(const std::vector<std::string>& args, bool* help) {
  CLI::App app = visionApp();
  AppOptions o;
  RawOptions raw;
  defineAppOptions(app, o, raw);
  if (auto ok = parseArgs(app, args, help); !ok) return ok.error();
  // The validators accepted these: the conversions cannot fail.
  if (!raw.robot_port.empty()) o.robot.port = static_cast<uint16_t>(*parseInt(raw.robot_port));
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
  if (!raw.min_area.empty()) o.vision.regions.min_area = *parseDouble(raw.min_area);
  if (!raw.curve_server_key.empty()) {
    auto keys = loadClientKeys(raw.curve_key, raw.curve_server_key);
    if (!keys) return keys.error();
    o.curve = std::move(*keys);
  }
  return o;
}

}  // namespace picksight::app
