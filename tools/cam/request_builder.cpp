// picksight-cam: the value checks of each command's arguments and the control
// request they fill. Argument counts were checked by the command line.
#include "request_builder.hpp"

#include <limits>
#include <optional>
#include <string>
#include <utility>

#include "picksight/codecs/codecs.hpp"

#include "cam_cli.hpp"
#include "picksight/common/text.hpp"

namespace picksight::cam {

namespace {

// Reads the arguments of one command; every error names the command.
class ArgReader {
 public:
  explicit ArgReader(const CamCommand& command) : command_(command) {}

  Error error(const std::string& name, const std::string& what) const {
    return usageError(command_.name + ": " + name + " " + what);
  }

  Result<std::uint32_t> uint32(const std::string& name) const {
    const std::string& text = command_.arg(name);
    const std::optional<long long> value = parseInt(text);
    if (!value || *value < 0)
      return error(name, "must be a non-negative integer, got '" + text + "'");
    if (*value > std::numeric_limits<std::uint32_t>::max()) {
      return error(name, "is too large, got '" + text + "'");
    }
    return static_cast<std::uint32_t>(*value);
  }

  Result<double> positive(const std::string& name) const {
    const std::string& text = command_.arg(name);
    const std::optional<double> value = parseDouble(text);
    if (!value || !(*value > 0))
      return error(name, "must be a positive number, got '" + text + "'");
    return *value;
  }

  Result<double> number(const std::string& name) const {
    const std::string& text = command_.arg(name);
    const std::optional<double> value = parseDouble(text);
    if (!value) return error(name, "must be a number, got '" + text + "'");
    return *value;
  }

  Result<std::string> word(const std::string& name) const {
    const std::string& text = command_.arg(name);
    if (text.empty()) return error(name, "must not be empty");
    return text;
  }

 private:
  const CamCommand& command_;
};

Result<proto::ControlRequest> buildRoi(const ArgReader& a, const std::string& camera) {
  std::uint32_t v[4] = {};
  const char* names[] = {"X", "Y", "W", "H"};
  for (int i = 0; i < 4; ++i) {
    auto parsed = a.uint32(names[i]);
    if (!parsed) return parsed.error();
    v[i] = *parsed;
  }
  proto::ControlRequest request;
  auto* roi_request = request.mutable_set_roi();
  roi_request->set_camera(camera);
  auto* roi = roi_request->mutable_roi();
  roi->set_x(v[0]);
  roi->set_y(v[1]);
  roi->set_width(v[2]);
  roi->set_height(v[3]);
  return request;
}

Result<proto::ControlRequest> buildSize(const CamCommand& c, const ArgReader& a,
                                        const std::string& camera) {
  proto::ControlRequest request;
  auto* size = request.mutable_set_size();
  size->set_camera(camera);
  if (c.has("S")) {
    auto scale = a.positive("S");
    if (!scale) return scale.error();
    size->set_scale(*scale);
    return request;
  }
  auto width = a.uint32("W");
  if (!width) return width.error();
  auto height = a.uint32("H");
  if (!height) return height.error();
  size->set_width(*width);
  size->set_height(*height);
  return request;
}

// The GenICam TriggerActivation for a short word (rising...) or the name itself.
Result<std::string> triggerActivation(const std::string& word) {
  static const std::pair<const char*, const char*> kEdges[] = {{"rising", "RisingEdge"},
                                                               {"falling", "FallingEdge"},
                                                               {"any", "AnyEdge"},
                                                               {"high", "LevelHigh"},
                                                               {"low", "LevelLow"}};
  for (const auto& [short_name, genicam] : kEdges) {
    if (word == short_name || word == genicam) return std::string(genicam);
  }
  return usageError("mode: --activation must be rising, falling, any, high or low, got '" + word +
                    "'");
}

Result<proto::ControlRequest> buildMode(const CamCommand& c, const ArgReader& a,
                                        const std::string& camera) {
  proto::ControlRequest request;
  auto* mode = request.mutable_set_mode();
  mode->set_camera(camera);
  const std::string& word = c.arg("MODE");
  if (word == "freerun") {
    mode->set_mode(proto::FREERUN);
  } else if (word == "trigger") {
    mode->set_mode(proto::TRIGGER);
  } else if (word == "hardware") {
    mode->set_mode(proto::HARDWARE_TRIGGER);
    if (c.has("LINE")) {
      auto line = a.word("LINE");
      if (!line) return line.error();
      mode->set_trigger_line(*line);
    }
    if (c.has("ACTIVATION")) {
      auto edge = triggerActivation(c.arg("ACTIVATION"));
      if (!edge) return edge.error();
      mode->set_trigger_activation(*edge);
    }
    if (c.has("TRIGGER_TIMEOUT")) {
      auto ms = a.uint32("TRIGGER_TIMEOUT");
      if (!ms) return ms.error();
      if (*ms == 0) return usageError("mode: --trigger-timeout must be positive");
      mode->set_trigger_timeout_ms(*ms);
    }
  } else {
    return usageError("mode: mode must be 'freerun', 'trigger' or 'hardware', got '" + word + "'");
  }
  if (c.has("FPS")) {
    auto fps = a.positive("FPS");
    if (!fps) return fps.error();
    mode->set_fps(*fps);
  }
  return request;
}

Result<proto::ControlRequest> buildFormat(const CamCommand& c, const std::string& camera) {
  proto::ControlRequest request;
  auto* format = request.mutable_set_format();
  format->set_camera(camera);
  const std::string& word = c.arg("FORMAT");
  if (word == "mono8") {
    format->set_pixel_format(proto::MONO8);
  } else if (word == "bgr8") {
    format->set_pixel_format(proto::BGR8);
  } else {
    return usageError("format: format must be 'mono8' or 'bgr8', got '" + word + "'");
  }
  return request;
}

// "get CAM FEATURE" and "set CAM FEATURE VALUE".
Result<proto::ControlRequest> buildFeature(const CamCommand& c, const ArgReader& a,
                                           const std::string& camera) {
  auto feature = a.word("FEATURE");
  if (!feature) return feature.error();
  proto::ControlRequest request;
  if (c.name == "get") {
    request.mutable_get_feature()->set_camera(camera);
    request.mutable_get_feature()->set_name(*feature);
    return request;
  }
  // An empty VALUE stays allowed: it is a legitimate value of a string feature.
  auto* set_feature = request.mutable_set_feature();
  set_feature->set_camera(camera);
  set_feature->set_name(*feature);
  set_feature->set_value(c.arg("VALUE"));
  return request;
}

Result<proto::ControlRequest> buildSnap(const ArgReader& a, const std::string& camera) {
  auto file = a.word("FILE");
  if (!file) return file.error();
  // Checked before asking: a snap in trigger mode takes a frame that the
  // vision apps receive too, which should not happen for a file never written.
  if (!picksight::codecs::haveImageWriter(*file)) {
    return usageError("snap: no image writer for '" + *file +
                      "'; the extension names the format (.png, .jpg, .tiff, .bmp)");
  }
  proto::ControlRequest request;
  request.mutable_snap()->set_camera(camera);
  return request;
}

Result<proto::ControlRequest> buildTarget(const CamCommand& c, const ArgReader& a,
                                          const std::string& camera) {
  proto::ControlRequest request;
  auto* target = request.mutable_set_target();
  target->set_camera(camera);
  if (c.has("HIDE")) {
    target->set_hide(true);
    return request;
  }
  auto x = a.number("X");
  if (!x) return x.error();
  auto y = a.number("Y");
  if (!y) return y.error();
  target->set_x_mm(*x);
  target->set_y_mm(*y);
  return request;
}

}  // namespace

Result<proto::ControlRequest> buildRequest(const CamCommand& c) {
  const ArgReader a(c);
  proto::ControlRequest request;
  if (c.name == "list") {
    request.mutable_list_cameras();
    return request;
  }
  if (c.name == "stats") {
    auto* stats = request.mutable_statistics();
    if (c.has("CAM")) {
      auto camera = a.word("CAM");
      if (!camera) return camera.error();
      stats->set_camera(*camera);
    }
    return request;
  }
  // Every other command starts with the camera.
  auto camera = a.word("CAM");
  if (!camera) return camera.error();
  if (c.name == "info") {
    request.mutable_describe_camera()->set_camera(*camera);
  } else if (c.name == "trigger") {
    request.mutable_trigger()->set_camera(*camera);
  } else if (c.name == "features") {
    request.mutable_list_features()->set_camera(*camera);
  } else if (c.name == "open") {
    request.mutable_open_stream()->set_camera(*camera);
  } else if (c.name == "close") {
    request.mutable_close_stream()->set_camera(*camera);
  } else if (c.name == "roi") {
    return buildRoi(a, *camera);
  } else if (c.name == "size") {
    return buildSize(c, a, *camera);
  } else if (c.name == "mode") {
    return buildMode(c, a, *camera);
  } else if (c.name == "format") {
    return buildFormat(c, *camera);
  } else if (c.name == "get" || c.name == "set") {
    return buildFeature(c, a, *camera);
  } else if (c.name == "snap") {
    return buildSnap(a, *camera);
  } else if (c.name == "target") {
    return buildTarget(c, a, *camera);
  } else {
    return usageError("unknown command '" + c.name + "'");
  }
  return request;
}

}  // namespace picksight::cam
