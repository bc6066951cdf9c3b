// JSON bodies of the camera actions to control requests and back.
#include "picksight/web/camera_actions.hpp"

#include <cmath>
#include <limits>
#include <optional>

#include "picksight/web/proto_json.hpp"
#include "picksight/web/web_errors.hpp"

namespace picksight::web {
namespace {

// Bounds of the hardware trigger's settings: GenICam names are short, and
// a pulse an hour late is a broken wire rather than a slow machine.
constexpr size_t kMaxTriggerName = 64;
constexpr uint32_t kMaxTriggerTimeoutMs = 3600000;

Error fieldError(const std::string& field, const std::string& what) {
  return makeError(WebErrc::kBadRequest, "\"" + field + "\": " + what);
}

// A number field; nullopt when absent (the caller decides if it must be there).
Result<std::optional<double>> number(const nlohmann::json& body, const std::string& field) {
  auto it = body.find(field);
  if (it == body.end() || it->is_null()) return std::optional<double>();
  if (!it->is_number()) return fieldError(field, "must be a number");
  const double v = it->get<double>();
  if (!std::isfinite(v)) return fieldError(field, "must be finite");
  return std::optional<double>(v);
}

// A whole number in [0, 65535] (pixels): absent is 0.
Result<uint32_t> pixels(const nlohmann::json& body, const std::string& field) {
  auto v = number(body, field);
  if (!v) return v.error();
  const double x = v->value_or(0);
  if (x < 0 || x > 65535 || x != std::floor(x))
    return fieldError(field, "must be a whole number of pixels, 0..65535");
  return static_cast<uint32_t>(x);
}

Result<std::string> text(const nlohmann::json& body, const std::string& field, bool required) {
  auto it = body.find(field);
  if (it == body.end() || it->is_null()) {
    if (required) return fieldError(field, "missing");
    return std::string();
  }
  if (it->is_string()) return it->get<std::string>();
  // Feature values may come as numbers or booleans from a form.
  if (it->is_number() || it->is_boolean()) return it->dump();
  return fieldError(field, "must be a string");
}

}  // namespace

std::string plainJsonMessage(const nlohmann::json::exception& e) {
  std::string message = e.what();
  // "[json.exception.out_of_range.406] number overflow ...": the tag names
  // the library's internals, the rest the problem.
  if (message.rfind("[json.exception.", 0) == 0) {
    const size_t end = message.find("] ");
    if (end != std::string::npos) message.erase(0, end + 2);
  }
  return message;
}

Result<nlohmann::json> parseJsonBody(const std::string& body) {
  if (body.find_first_not_of(" \t\r\n") == std::string::npos) return nlohmann::json::object();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(body);
  } catch (const nlohmann::json::exception& e) {
    // Syntax errors and numbers out of range ({"line": 1e999}) alike: the
    // parser's words say where and what, without its exception's tag.
    return makeError(WebErrc::kBadRequest, "bad JSON: " + plainJsonMessage(e));
  }
  if (!j.is_object()) return makeError(WebErrc::kBadRequest, "the body must be a JSON object");
  return j;
}

namespace {
// The size action: a scale, or a width and a height.
Result<void> sizeAction(proto::SetSizeRequest* size, const nlohmann::json& body) {
  auto scale = number(body, "scale");
  if (!scale) return scale.error();
  if (*scale) {
    if (**scale <= 0 || **scale > 16) return fieldError("scale", "must be in (0, 16]");
    size->set_scale(**scale);
  } else {
    auto w = pixels(body, "width");
    if (!w) return w.error();
    auto h = pixels(body, "height");
    if (!h) return h.error();
    size->set_width(*w);
    size->set_height(*h);
  }
  return {};
}

// The mode action: the mode, the hardware trigger's input, the rate.
Result<void> modeAction(proto::SetModeRequest* mode, const nlohmann::json& body) {
  auto name = text(body, "mode", true);
  if (!name) return name.error();
  if (*name == "freerun") {
    mode->set_mode(proto::FREERUN);
  } else if (*name == "trigger") {
    mode->set_mode(proto::TRIGGER);
  } else if (*name == "hardware") {
    mode->set_mode(proto::HARDWARE_TRIGGER);
  } else {
    return fieldError("mode", "must be \"freerun\", \"trigger\" or \"hardware\"");
  }
  // The trigger input's settings go with the hardware mode only, as with
  // picksight-cam; their names and values are the video server's to judge
  // (it names the camera's choices when it refuses one).
  for (const char* field : {"line", "activation", "timeout_ms"}) {
    if (mode->mode() != proto::HARDWARE_TRIGGER && body.contains(field) &&
        !body.at(field).is_null())
      return fieldError(field, "goes with the \"hardware\" mode only");
  }
  for (const char* field : {"line", "activation"}) {
    auto value = text(body, field, false);
    if (!value) return value.error();
    if (value->size() > kMaxTriggerName) {
      return fieldError(field, "longer than " + std::to_string(kMaxTriggerName) + " bytes");
    }
    if (field[0] == 'l') mode->set_trigger_line(*value);
    if (field[0] == 'a') mode->set_trigger_activation(*value);
  }
  auto timeout = number(body, "timeout_ms");
  if (!timeout) return timeout.error();
  if (*timeout) {
    const double ms = **timeout;
    if (ms < 1 || ms > kMaxTriggerTimeoutMs || ms != std::floor(ms)) {
      return fieldError("timeout_ms", "must be a whole number of milliseconds, 1.." +
                                          std::to_string(kMaxTriggerTimeoutMs));
    }
    mode->set_trigger_timeout_ms(static_cast<uint32_t>(ms));
  }
  auto fps = number(body, "fps");
  if (!fps) return fps.error();
  if (*fps && (**fps < 0 || **fps > 10000)) return fieldError("fps", "must be in 0..10000");
  mode->set_fps(fps->value_or(0));
  return {};
}

// The simulated robot's target: hidden, or placed at x_mm, y_mm.
Result<void> targetAction(proto::SetTargetRequest* target, const nlohmann::json& body) {
  auto hide = body.find("hide");
  if (hide != body.end() && !hide->is_boolean()) return fieldError("hide", "must be true or false");
  if (hide != body.end() && hide->get<bool>()) {
    target->set_hide(true);
  } else {
    auto x = number(body, "x_mm");
    if (!x) return x.error();
    auto y = number(body, "y_mm");
    if (!y) return y.error();
    if (!*x || !*y) return fieldError(*x ? "y_mm" : "x_mm", "missing");
    target->set_x_mm(**x);
    target->set_y_mm(**y);
  }
  return {};
}

}  // namespace

Result<proto::ControlRequest> cameraAction(const std::string& camera, const std::string& action,
                                           const nlohmann::json& body) {
  proto::ControlRequest request;
  if (action == "roi") {
    auto* roi = request.mutable_set_roi();
    roi->set_camera(camera);
    for (const char* field : {"x", "y", "width", "height"}) {
      auto v = pixels(body, field);
      if (!v) return v.error();
      auto* r = roi->mutable_roi();
      if (field[0] == 'x') r->set_x(*v);
      if (field[0] == 'y') r->set_y(*v);
      if (field[0] == 'w') r->set_width(*v);
      if (field[0] == 'h') r->set_height(*v);
    }
  } else if (action == "size") {
    auto* size = request.mutable_set_size();
    size->set_camera(camera);
    if (auto ok = sizeAction(size, body); !ok) return ok.error();
  } else if (action == "mode") {
    auto* mode = request.mutable_set_mode();
    mode->set_camera(camera);
    if (auto ok = modeAction(mode, body); !ok) return ok.error();
  } else if (action == "feature") {
    auto* feature = request.mutable_set_feature();
    feature->set_camera(camera);
    auto name = text(body, "name", true);
    if (!name) return name.error();
    auto value = text(body, "value", false);
    if (!value) return value.error();
    if (name->empty() || name->size() > 256) return fieldError("name", "must be 1..256 bytes");
    if (value->size() > 4096) return fieldError("value", "longer than 4096 bytes");
    feature->set_name(*name);
    feature->set_value(*value);
  } else if (action == "open") {
    request.mutable_open_stream()->set_camera(camera);
  } else if (action == "close") {
    request.mutable_close_stream()->set_camera(camera);
  } else if (action == "trigger") {
    request.mutable_trigger()->set_camera(camera);
  } else if (action == "target") {
    auto* target = request.mutable_set_target();
    target->set_camera(camera);
    if (auto ok = targetAction(target, body); !ok) return ok.error();
  } else {
    return makeError(WebErrc::kNotFound, "no camera action '" + action + "'");
  }
  return request;
}

nlohmann::json actionReplyJson(const proto::ControlReply& reply) {
  nlohmann::json out = {{"ok", true}};
  switch (reply.reply_case()) {
    case proto::ControlReply::kTrigger:
      out["sequence"] = reply.trigger().sequence();
      out["triggered"] = reply.trigger().triggered();
      break;
    case proto::ControlReply::kFeature:
      out["feature"] = protoJson(reply.feature().feature(), true);
      break;
    case proto::ControlReply::kSimulatedRobot:
      out["simulated_robot"] = protoJson(reply.simulated_robot(), true);
      break;
    default:
      break;
  }
  return out;
}

}  // namespace picksight::web
