// Command-line (picksight::cli) and YAML configuration of the video server.
#include "picksight/video_server/server_config.hpp"

#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <optional>
#include <set>

#include "picksight/cli/command_line.hpp"
#include "picksight/common/text.hpp"
#include "picksight/video_server/video_errors.hpp"

namespace picksight::video {
namespace {

Result<AcquisitionMode> parseMode(const std::string& text) {
  if (text == "freerun") return AcquisitionMode::kFreeRun;
  if (text == "trigger") return AcquisitionMode::kTrigger;
  if (text == "hardware") return AcquisitionMode::kHardwareTrigger;
  return makeError(VideoErrc::kBadConfig,
                   "must be freerun, trigger or hardware, got '" + text + "'");
}

Result<OutputFormat> parseFormat(const std::string& text) {
  if (text == "mono8") return OutputFormat::kMono8;
  if (text == "bgr8") return OutputFormat::kBgr8;
  return makeError(VideoErrc::kBadConfig, "must be mono8 or bgr8, got '" + text + "'");
}

Result<double> parseFps(const std::string& text) {
  auto v = parseDouble(text);
  if (!v || *v <= 0 || *v > kMaxFps) {
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

// trigger_line, trigger_activation (GenICam names) and trigger_timeout
// (seconds) of one camera.
Result<void> hardwareTriggerFromYaml(const YAML::Node& node, const std::string& where,
                                     HardwareTrigger& out) {
  if (const YAML::Node line = node["trigger_line"]) {
    if (!line.IsScalar() || line.Scalar().empty() || line.Scalar().size() > 64) {
      return makeError(VideoErrc::kBadConfig,
                       where + ".trigger_line: must be the camera's input, e.g. Line1");
    }
    out.input.line = line.Scalar();
  }
  if (const YAML::Node edge = node["trigger_activation"]) {
    if (!edge.IsScalar() || !isTriggerActivation(edge.Scalar())) {
      return makeError(VideoErrc::kBadConfig,
                       where + ".trigger_activation: must be one of " + kTriggerActivations);
    }
    out.input.activation = edge.Scalar();
  }
  if (const YAML::Node timeout = node["trigger_timeout"]) {
    auto t = parseDouble(timeout.Scalar());
    if (!timeout.IsScalar() || !t || !(*t >= 0.01 && *t <= 3600)) {
      return makeError(VideoErrc::kBadConfig,
                       where + ".trigger_timeout: must be seconds in [0.01, 3600]");
    }
    out.timeout = std::chrono::milliseconds(std::llround(*t * 1000));
  }
  return {};
}

Result<CameraConfig> cameraFromYaml(const YAML::Node& node, const std::string& where) {
  if (!node.IsMap()) return makeError(VideoErrc::kBadConfig, where + ": must be a map");
  CameraConfig c;
  static const std::set<std::string> kKeys = {"name",           "source",
                                              "mode",           "fps",
                                              "format",         "roi",
                                              "size",           "scale",
                                              "features",       "no_frame_timeout",
                                              "trigger_line",   "trigger_activation",
                                              "trigger_timeout"};
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
    c.mode_asked = true;
  }
  if (node["fps"]) {
    auto f = parseFps(node["fps"].Scalar());
    if (!f) return makeError(VideoErrc::kBadConfig, where + ".fps: " + f.error().message);
    c.fps = *f;
    c.fps_asked = true;
  }
  if (node["no_frame_timeout"]) {
    auto t = parseDouble(node["no_frame_timeout"].Scalar());
    if (!t || !(*t >= 0.1 && *t <= 3600)) {
      return makeError(VideoErrc::kBadConfig,
                       where + ".no_frame_timeout: must be seconds in [0.1, 3600]");
    }
    c.no_frame_timeout = std::chrono::milliseconds(std::llround(*t * 1000));
  }
  if (auto ok = hardwareTriggerFromYaml(node, where, c.hardware); !ok) return ok.error();
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
    if (!s || *s <= 0 || *s > kMaxOutputScale)
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

// The `curve:` map: secret_key (the server's NAME.key_secret) and clients
// (the allow-list).
Result<void> curveFromYaml(const YAML::Node& node, ServerConfig& config) {
  if (!node.IsMap()) return makeError(VideoErrc::kBadConfig, "curve: must be a map");
  for (const auto& kv : node) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "";
    if (key != "secret_key" && key != "clients") {
      return makeError(VideoErrc::kBadConfig,
                       "curve." + key + ": unknown key (known: secret_key, clients)");
    }
    if (!kv.second.IsScalar() || kv.second.Scalar().empty()) {
      return makeError(VideoErrc::kBadConfig, "curve." + key + ": must be a file name");
    }
    (key == "secret_key" ? config.curve_secret_key : config.curve_allow_list) = kv.second.Scalar();
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
    if (key != "frames" && key != "control" && key != "cameras" && key != "curve") {
      return makeError(
          VideoErrc::kBadConfig,
          path + ": " + key + ": unknown key (known: frames, control, cameras, curve)");
    }
  }
  if (root["curve"]) {
    if (auto ok = curveFromYaml(root["curve"], config); !ok)
      return makeError(VideoErrc::kBadConfig, path + ": " + ok.error().message);
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

namespace {

// The command line before it is applied to the configuration.
struct ServerArgs {
  std::string config_file;
  std::vector<std::string> sources;
  std::string frames;
  std::string control;
  std::string mode;
  std::string fps;
  std::string curve_secret_key;
  std::string curve_allow_list;
};

// Declares the options on `app`, bound to `a`; both parseServerArgs and
// serverUsage use it, so the help lists exactly what is parsed.
void defineServerOptions(cli::App& app, ServerArgs& a) {
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--config", a.config_file,
                "YAML file with frames, control and cameras (see deploy/examples)")
      ->typeName("FILE");
  app.addOption("--source", a.sources, "a camera (default: cam0=synthetic:), repeatable")
      ->typeName("NAME=URI")
      ->check(cli::checkValue([](const std::string& v) {
        const size_t eq = v.find('=');
        if (eq == std::string::npos || eq == 0 || eq + 1 == v.size()) {
          return "expected NAME=URI, got '" + v + "'";
        }
        return std::string();
      }));
  app.addOption("--frames", a.frames, "frame PUB endpoint (default tcp://*:5555)")
      ->typeName("ENDPOINT");
  app.addOption("--control", a.control, "control REP endpoint (default tcp://*:5556)")
      ->typeName("ENDPOINT");
  app.addOption("--mode", a.mode, "acquisition mode of the --source cameras (default freerun)")
      ->typeName("freerun|trigger|hardware")
      ->check(cli::checkValue([](const std::string& v) {
        auto m = parseMode(v);
        return m ? std::string() : m.error().message;
      }));
  app.addOption("--fps", a.fps,
                "free-run frame rate of the --source cameras (default: a camera's own, 10 for "
                "the others)")
      ->typeName("F")
      ->check(cli::checkValue([](const std::string& v) {
        auto f = parseFps(v);
        return f ? std::string() : f.error().message;
      }));
  app.addOption("--curve-secret-key", a.curve_secret_key,
                "CURVE: encrypt control and seal frames (once each, for every subscriber); "
                "the server's NAME.key_secret "
                "(picksight-keygen; see docs/SECURITY.md)")
      ->typeName("FILE");
  app.addOption("--curve-clients", a.curve_allow_list,
                "admit only these CURVE clients: a directory of their NAME.key files, or one "
                "file of public-key lines (without it any client knowing the server's public "
                "key gets in)")
      ->typeName("DIR|FILE");
  app.footer(
      "Sources (URI):\n"
      "  aravis:<device-id>        GigE Vision / USB3 Vision (empty id: first found)\n"
      "  v4l2:/dev/videoN[?width=W&height=H&format=yuyv|mjpeg&fps=F]\n"
      "  stream:<url>              RTSP, HTTP MJPEG, any file FFmpeg reads\n"
      "  file:<path>               one image, re-read when it changes\n"
      "  dir:<path>                images in name order, looping\n"
      "  synthetic:[key=value,...] generated scene with ground truth\n"
      "    (width, height, parts, seed, noise, size, light, types, touching, blur,\n"
      "    scene_every; the simulated robot: mm_per_px, rz, dx, dy, tilt_x, tilt_y,\n"
      "    target=disc|grid, target_radius, grid=COLSxROWS, grid_pitch)\n"
      "\n"
      "On start it prints 'frames <endpoint>' and 'control <endpoint>' on stdout.");
}

cli::App serverApp() {
  return cli::App("Publishes camera frames over ZeroMQ and serves camera configuration.",
                  "picksight-video-server");
}

}  // namespace

std::string serverUsage() {
  cli::App app = serverApp();
  ServerArgs unused;
  defineServerOptions(app, unused);
  return app.help();
}

Result<ServerConfig> parseServerArgs(const std::vector<std::string>& args, bool* help) {
  cli::App app = serverApp();
  ServerArgs a;
  defineServerOptions(app, a);
  bool wants_help = false;
  if (auto ok = cli::parseArgs(app, args, &wants_help, VideoErrc::kBadConfig); !ok)
    return ok.error();
  if (help) *help = wants_help;
  ServerConfig config;
  if (wants_help) return config;
  // The file first: options given next to --config override what it says.
  if (!a.config_file.empty()) {
    auto loaded = loadServerConfig(a.config_file);
    if (!loaded) return loaded.error();
    config = std::move(*loaded);
  }
  std::optional<AcquisitionMode> mode;
  std::optional<double> fps;
  if (!a.mode.empty()) mode = *parseMode(a.mode);  // checked by the option
  if (!a.fps.empty()) fps = *parseFps(a.fps);
  auto apply = [&](CameraConfig& c) {
    if (mode) {
      c.mode = *mode;
      c.mode_asked = true;
    }
    if (fps) {
      c.fps = *fps;
      c.fps_asked = true;
    }
  };
  for (const std::string& source : a.sources) {
    const size_t eq = source.find('=');
    CameraConfig c;
    c.name = source.substr(0, eq);
    c.uri = source.substr(eq + 1);
    apply(c);
    config.cameras.push_back(c);
  }
  if (!a.frames.empty()) config.frames_endpoint = a.frames;
  if (!a.control.empty()) config.control_endpoint = a.control;
  if (!a.curve_secret_key.empty()) config.curve_secret_key = a.curve_secret_key;
  if (!a.curve_allow_list.empty()) config.curve_allow_list = a.curve_allow_list;
  if (config.cameras.empty()) {
    CameraConfig c;
    c.name = "cam0";
    c.uri = "synthetic:";
    apply(c);
    config.cameras.push_back(c);
  }
  if (auto ok = checkUniqueNames(config.cameras); !ok) return ok.error();
  return config;
}

}  // namespace picksight::video
