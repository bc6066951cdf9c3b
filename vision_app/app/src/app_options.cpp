// picksight-vision option parsing.
#include "picksight/vision_app/app_options.hpp"

#include "picksight/common/text.hpp"

namespace picksight::app {

std::string appUsage() {
  return "usage: picksight-vision [--frames ENDPOINT] [--control ENDPOINT] [--camera NAME]\n"
         "         [--robot-port PORT] [--bind ADDRESS] [--data-dir DIR]\n"
         "         [--threshold adaptive|otsu|fixed:LEVEL] [--polarity dark|light]\n"
         "         [--window PIXELS] [--min-area PIXELS]\n"
         "\n"
         "  --frames E       video server frame endpoint (default tcp://127.0.0.1:5555)\n"
         "  --control E      video server control endpoint (default tcp://127.0.0.1:5556)\n"
         "  --camera NAME    camera to watch (default cam0)\n"
         "  --robot-port P   TCP port for robot controllers (default 5600, 0 = any free)\n"
         "  --bind ADDRESS   address the robot port listens on (default 0.0.0.0)\n"
         "  --data-dir DIR   models and calibrations (default ./picksight-data)\n"
         "  --threshold M    binarization (default adaptive)\n"
         "  --polarity P     dark parts on light background (default) or light on dark\n"
         "  --window PIXELS  adaptive illumination window, wider than the largest part\n"
         "  --min-area PX    smallest region that counts as a part (default 50)\n"
         "\n"
         "On start it prints 'robot <port>' and 'ready' on stdout.\n";
}

Result<AppOptions> parseAppArgs(const std::vector<std::string>& args, bool* help) {
  AppOptions o;
  if (help) *help = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") {
      if (help) *help = true;
      return o;
    }
    if (i + 1 >= args.size())
      return makeError(OptionsErrc::kBadOption, a + ": missing value or unknown option");
    const std::string& v = args[++i];
    if (a == "--frames") {
      o.frames_endpoint = v;
    } else if (a == "--control") {
      o.control_endpoint = v;
    } else if (a == "--camera") {
      o.camera = v;
    } else if (a == "--data-dir") {
      o.data_dir = v;
    } else if (a == "--bind") {
      o.robot.bind_address = v;
    } else if (a == "--robot-port") {
      auto p = parseInt(v);
      if (!p || *p < 0 || *p > 65535)
        return makeError(OptionsErrc::kBadOption,
                         "--robot-port: must be in [0, 65535], got '" + v + "'");
      o.robot.port = static_cast<uint16_t>(*p);
    } else if (a == "--threshold") {
      if (v == "adaptive") {
        o.vision.binarize.method = vision::ThresholdMethod::kAdaptive;
      } else if (v == "otsu") {
        o.vision.binarize.method = vision::ThresholdMethod::kOtsu;
      } else if (v.rfind("fixed:", 0) == 0) {
        auto level = parseInt(v.substr(6));
        if (!level || *level < 0 || *level > 255) {
          return makeError(OptionsErrc::kBadOption,
                           "--threshold: fixed level must be in [0, 255], got '" + v + "'");
        }
        o.vision.binarize.method = vision::ThresholdMethod::kFixed;
        o.vision.binarize.fixed_threshold = static_cast<int>(*level);
      } else {
        return makeError(OptionsErrc::kBadOption,
                         "--threshold: must be adaptive, otsu or fixed:LEVEL, got '" + v + "'");
      }
    } else if (a == "--polarity") {
      if (v != "dark" && v != "light")
        return makeError(OptionsErrc::kBadOption,
                         "--polarity: must be dark or light, got '" + v + "'");
      o.vision.binarize.polarity =
          v == "dark" ? vision::Polarity::kDarkOnLight : vision::Polarity::kLightOnDark;
    } else if (a == "--window") {
      auto w = parseInt(v);
      if (!w || *w < 8 || *w > 16384)
        return makeError(OptionsErrc::kBadOption,
                         "--window: must be in [8, 16384], got '" + v + "'");
      o.vision.binarize.adaptive_window = static_cast<int>(*w);
    } else if (a == "--min-area") {
      auto m = parseDouble(v);
      if (!m || *m < 1)
        return makeError(OptionsErrc::kBadOption,
                         "--min-area: must be a number >= 1, got '" + v + "'");
      o.vision.regions.min_area = *m;
    } else {
      return makeError(OptionsErrc::kBadOption, "unknown option '" + a + "'");
    }
  }
  return o;
}

}  // namespace picksight::app
