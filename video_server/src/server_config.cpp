// Command-line and YAML configuration of the video server.
#include "picksight/video_server/server_config.hpp"
#include "picksight/video_server/video_errors.hpp"

#include <yaml-cpp/yaml.h>

#include <optional>
#include <set>

#include "picksight/common/text.hpp"

namespace picksight::video {
namespace {

Result<AcquisitionMode> parseMode(const std::string& text) {
  if (text == "freerun") return AcquisitionMode::kFreeRun;
  if (text == "trigger") return AcquisitionMode::kTrigger;
  return makeError(VideoErrc::kBadConfig, "must be freerun or trigger, got '" + text + "'");
}

Result<OutputFormat> parseFormat(const std::string& text) {
  if (text == "mono8") return OutputFormat::kMono8;
  if (text == "bgr8") return OutputFormat::kBgr8;
  return makeError(VideoErrc::kBadConfig, "must be mono8 or bgr8, got '" + text + "'");
}

Result<double> parseFps(const std::string& text) {
  auto v = parseDouble(text);
  if (!v || *v <= 0 || *v > 1000) {
    return makeError(VideoErrc::kBadConfig, "must be a number in (0, 1000], got '" + text + "'");
  }
  return *v;
}

// Reads `key` of a YAML map as a list of N non-negative integers.
Result<std::vector<int>> intList(const YAML::Node& node, size_t n) {
  if (!node.IsSequence() || node.size() != n) {
    return makeError(VideoErrc::kBadConfig, "must be a list of " + std::to_string(n) + " integers");
  }
  std::vector<int> out;
  for (const auto& item : node) {
    auto v = parseInt(item.Scalar());
    if (!item.IsScalar() || !v || *v < 0 || *v > 100000) {
      return makeError(VideoErrc::kBadConfig,
                       "must be a list of " + std::to_string(n) + " non-negative integers");
    }
    out.push_back(static_cast<int>(*v));
  }
  return out;
}

Result<CameraConfig> cameraFromYaml(const YAML::Node& node, const std::string& where) {
  if (!node.IsMap()) return makeError(VideoErrc::kBadConfig, where + ": must be a map");
  CameraConfig c;
  static const std::set<std::string> kKeys = {"name", "source", "mode",  "fps",     "format",
                                              "roi",  "size",   "scale", "features"};
  for (const auto& kv : node) {
    // as<std::string>() throws on a key that is a list or a map.
    if (!kv.first.IsScalar())
      return makeError(VideoErrc::kBadConfig, where + ": keys must be plain names");
    const std::string key = kv.first.Scalar();
    if (!kKeys.count(key))
      return makeError(VideoErrc::kBadConfig, where + "." + key + ": unknown key");
  }
  if (!node["name"] || !node["name"].IsScalar() || node["name"].Scalar().empty()) {
    return makeError(VideoErrc::kBadConfig, where + ".name: required");
  }
  c.name = node["name"].Scalar();
  if (!node["source"] || !node["source"].IsScalar()) {
    return makeError(VideoErrc::kBadConfig, where + ".source: required (e.g. synthetic:)");
  }
  c.uri = node["source"].Scalar();
  if (node["mode"]) {
    auto m = parseMode(node["mode"].Scalar());
    if (!m) return makeError(VideoErrc::kBadConfig, where + ".mode: " + m.error().message);
    c.mode = *m;
  }
  if (node["fps"]) {
    auto f = parseFps(node["fps"].Scalar());
    if (!f) return makeError(VideoErrc::kBadConfig, where + ".fps: " + f.error().message);
    c.fps = *f;
  }
  if (node["format"]) {
    auto f = parseFormat(node["format"].Scalar());
    if (!f) return makeError(VideoErrc::kBadConfig, where + ".format: " + f.error().message);
    c.output.format = *f;
  }
  if (node["roi"]) {
    auto r = intList(node["roi"], 4);
    if (!r)
      return makeError(VideoErrc::kBadConfig,
                       where + ".roi: " + r.error().message + " [x, y, width, height]");
    c.output.roi = cv::Rect((*r)[0], (*r)[1], (*r)[2], (*r)[3]);
  }
  if (node["size"]) {
    auto s = intList(node["size"], 2);
    if (!s)
      return makeError(VideoErrc::kBadConfig,
                       where + ".size: " + s.error().message + " [width, height]");
    c.output.size = cv::Size((*s)[0], (*s)[1]);
  }
  if (node["scale"]) {
    auto s = parseDouble(node["scale"].Scalar());
    if (!s || *s <= 0 || *s > 16)
      return makeError(VideoErrc::kBadConfig, where + ".scale: must be a number in (0, 16]");
    c.output.scale = *s;
  }
  if (node["features"]) {
    if (!node["features"].IsMap()) {
      return makeError(VideoErrc::kBadConfig,
                       where + ".features: must be a map of feature names to values");
    }
    for (const auto& kv : node["features"]) {
      const std::string key = kv.first.as<std::string>();
      if (!kv.second.IsScalar()) {
        return makeError(VideoErrc::kBadConfig,
                         where + ".features." + key + ": must be a single value");
      }
      c.features.emplace_back(key, kv.second.Scalar());
    }
  }
  if (auto ok = validateOutputSettings(c.output, cv::Size()); !ok) {
    return makeError(VideoErrc::kBadConfig, where + ": " + ok.error().message);
  }
  return c;
}

Result<void> checkUniqueNames(const std::vector<CameraConfig>& cameras) {
  std::set<std::string> seen;
  for (const auto& c : cameras) {
    if (!seen.insert(c.name).second)
      return makeError(VideoErrc::kBadConfig, "camera name '" + c.name + "' used twice");
  }
  return {};
}
}  // namespace

Result<ServerConfig> loadServerConfig(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    return makeError(VideoErrc::kBadConfig, path + ": " + e.what());
  }
  ServerConfig config;
  if (!root.IsMap()) return makeError(VideoErrc::kBadConfig, path + ": must be a YAML map");
  for (const auto& kv : root) {
    if (!kv.first.IsScalar())
      return makeError(VideoErrc::kBadConfig, path + ": keys must be plain names");
    const std::string key = kv.first.Scalar();
    if (key != "frames" && key != "control" && key != "cameras") {
      return makeError(VideoErrc::kBadConfig,
                       path + ": " + key + ": unknown key (known: frames, control, cameras)");
    }
  }
  if (root["frames"]) config.frames_endpoint = root["frames"].Scalar();
  if (root["control"]) config.control_endpoint = root["control"].Scalar();
  if (root["cameras"]) {
    if (!root["cameras"].IsSequence())
      return makeError(VideoErrc::kBadConfig, path + ": cameras: must be a list");
    for (size_t i = 0; i < root["cameras"].size(); ++i) {
      auto c = cameraFromYaml(root["cameras"][i], "cameras[" + std::to_string(i) + "]");
      if (!c) return makeError(VideoErrc::kBadConfig, path + ": " + c.error().message);
      config.cameras.push_back(std::move(*c));
    }
  }
  if (auto ok = checkUniqueNames(config.cameras); !ok)
    return makeError(VideoErrc::kBadConfig, path + ": " + ok.error().message);
  return config;
}

std::string serverUsage() {
  return "usage: picksight-video-server [--config FILE] [--source NAME=URI ...]\n"
         "         [--frames ENDPOINT] [--control ENDPOINT] [--mode freerun|trigger] [--fps F]\n"
         "\n"
         "  --source NAME=URI  a camera (default: cam0=synthetic:), one of\n"
         "                       aravis:<device-id>       GigE Vision / USB3 Vision (empty id: "
         "first found)\n"
         "                       v4l2:/dev/videoN[?width=W&height=H&format=yuyv|mjpeg&fps=F]\n"
         "                       stream:<url>             RTSP, HTTP MJPEG, any file FFmpeg reads\n"
         "                       file:<path>              one image, re-read when it changes\n"
         "                       dir:<path>               images in name order, looping\n"
         "                       synthetic:[key=value,...] generated scene with ground truth\n"
         "                         (width, height, parts, seed, noise, size, light, types, "
         "scene_every)\n"
         "  --frames E         frame PUB endpoint (default tcp://*:5555)\n"
         "  --control E        control REP endpoint (default tcp://*:5556)\n"
         "  --mode M           acquisition mode of the --source cameras (default freerun)\n"
         "  --fps F            free-run frame rate of the --source cameras (default 10)\n"
         "  --config FILE      YAML file with frames, control and cameras (see deploy/examples)\n"
         "\n"
         "On start it prints 'frames <endpoint>' and 'control <endpoint>' on stdout.\n";
}

Result<ServerConfig> parseServerArgs(const std::vector<std::string>& args, bool* help) {
  ServerConfig config;
  std::vector<CameraConfig> cli_cameras;
  std::optional<AcquisitionMode> mode;
  std::optional<double> fps;
  std::optional<std::string> frames;
  std::optional<std::string> control;
  if (help) *help = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") {
      if (help) *help = true;
      return config;
    }
    if (i + 1 >= args.size())
      return makeError(VideoErrc::kBadConfig, a + ": missing value or unknown option");
    const std::string& v = args[++i];
    if (a == "--config") {
      auto loaded = loadServerConfig(v);
      if (!loaded) return loaded.error();
      config = std::move(*loaded);
    } else if (a == "--source") {
      const size_t eq = v.find('=');
      if (eq == std::string::npos || eq == 0 || eq + 1 == v.size()) {
        return makeError(VideoErrc::kBadConfig, "--source: expected NAME=URI, got '" + v + "'");
      }
      CameraConfig c;
      c.name = v.substr(0, eq);
      c.uri = v.substr(eq + 1);
      cli_cameras.push_back(c);
    } else if (a == "--frames") {
      frames = v;
    } else if (a == "--control") {
      control = v;
    } else if (a == "--mode") {
      auto m = parseMode(v);
      if (!m) return makeError(VideoErrc::kBadConfig, "--mode: " + m.error().message);
      mode = *m;
    } else if (a == "--fps") {
      auto f = parseFps(v);
      if (!f) return makeError(VideoErrc::kBadConfig, "--fps: " + f.error().message);
      fps = *f;
    } else {
      return makeError(VideoErrc::kBadConfig, "unknown option '" + a + "'");
    }
  }
  for (auto& c : cli_cameras) {
    if (mode) c.mode = *mode;
    if (fps) c.fps = *fps;
    config.cameras.push_back(c);
  }
  if (frames) config.frames_endpoint = *frames;
  if (control) config.control_endpoint = *control;
  if (config.cameras.empty()) {
    CameraConfig c;
    c.name = "cam0";
    c.uri = "synthetic:";
    if (mode) c.mode = *mode;
    if (fps) c.fps = *fps;
    config.cameras.push_back(c);
  }
  if (auto ok = checkUniqueNames(config.cameras); !ok) return ok.error();
  return config;
}

}  // namespace picksight::video
