// A filmstrip entry's sidecar: JSON text and back, every field checked.
#include <nlohmann/json.hpp>

#include "picksight/common/text.hpp"
#include "picksight/filmstrip/filmstrip.hpp"

namespace picksight::filmstrip {

const char* errorName(FilmstripErrc e) {
  switch (e) {
    case FilmstripErrc::kNoEntry:
      return "no entry";
    case FilmstripErrc::kDamaged:
      return "damaged";
    case FilmstripErrc::kOff:
      return "off";
    case FilmstripErrc::kStorage:
      return "storage";
    case FilmstripErrc::kNoFrame:
      return "no frame";
  }
  return "unknown";
}

bool isFailureReply(const std::string& reply) {
  if (reply.rfind("OK", 0) != 0) return true;
  const auto fields = splitFields(reply, " ");
  return fields.size() < 2 || fields[1] == "0";
}

std::string entryJson(const Entry& e) {
  nlohmann::json parts = nlohmann::json::array();
  for (const auto& p : e.parts) {
    parts.push_back({{"type", p.type},
                     {"x", p.x},
                     {"y", p.y},
                     {"angle_deg", p.angle_deg},
                     {"score", p.score},
                     {"offered", p.offered}});
  }
  const nlohmann::json j = {
      {"id", e.id},
      {"time_ms", e.time_ms},
      {"request", e.request},
      {"request_line", e.request_line},
      {"reply", e.reply},
      {"reply_frame", e.reply_frame},
      {"client", e.client},
      {"failure", e.failure},
      {"asked_type", e.asked_type},
      {"elapsed_ms", e.elapsed_ms},
      {"camera", e.camera},
      {"sequence", e.sequence},
      {"mapping",
       {{"roi_x", e.mapping.roi_x},
        {"roi_y", e.mapping.roi_y},
        {"scale_x", e.mapping.scale_x},
        {"scale_y", e.mapping.scale_y}}},
      {"width", e.width},
      {"height", e.height},
      {"parts", parts},
      {"why", e.why},
      {"explains", e.explains},
      {"image", e.image},
  };
  // Client text may hold any byte: replaced, never a reason to lose the entry.
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

namespace {
// The field `key` of `j` as a T, or an error naming it.
template <typename T>
Result<T> field(const nlohmann::json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end()) return makeError(FilmstripErrc::kDamaged, std::string("no \"") + key + "\"");
  try {
    return it->get<T>();
  } catch (const nlohmann::json::exception&) {
    return makeError(FilmstripErrc::kDamaged, std::string("\"") + key + "\" has the wrong type");
  }
}
}  // namespace

Result<Entry> parseEntryJson(const std::string& text) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    return makeError(FilmstripErrc::kDamaged, std::string("not JSON: ") + e.what());
  }
  if (!j.is_object()) return makeError(FilmstripErrc::kDamaged, "not a JSON object");
  Entry e;
  // Every field read the same way: the first one missing or mistyped is
  // the error.
  std::optional<Error> bad;
  const auto read = [&](auto& into, const char* key) {
    if (bad) return;
    auto v = field<std::decay_t<decltype(into)>>(j, key);
    if (v) {
      into = std::move(*v);
    } else {
      bad = v.error();
    }
  };
  read(e.id, "id");
  read(e.time_ms, "time_ms");
  read(e.request, "request");
  read(e.request_line, "request_line");
  read(e.reply, "reply");
  read(e.client, "client");
  read(e.failure, "failure");
  read(e.asked_type, "asked_type");
  read(e.elapsed_ms, "elapsed_ms");
  read(e.camera, "camera");
  read(e.sequence, "sequence");
  read(e.why, "why");
  read(e.explains, "explains");
  read(e.image, "image");
  read(e.width, "width");
  read(e.height, "height");
  // Sidecars written before the reply's frame was recorded have none.
  if (j.contains("reply_frame")) read(e.reply_frame, "reply_frame");
  nlohmann::json mapping;
  nlohmann::json parts;
  read(mapping, "mapping");
  read(parts, "parts");
  if (bad) return *bad;
  if (!mapping.is_object() || !parts.is_array())
    return makeError(FilmstripErrc::kDamaged, "\"mapping\" or \"parts\" has the wrong type");
  const auto number = [&](const nlohmann::json& o, const char* key, auto& into) {
    if (bad) return;
    auto v = field<std::decay_t<decltype(into)>>(o, key);
    if (v) {
      into = *v;
    } else {
      bad = v.error();
    }
  };
  number(mapping, "roi_x", e.mapping.roi_x);
  number(mapping, "roi_y", e.mapping.roi_y);
  number(mapping, "scale_x", e.mapping.scale_x);
  number(mapping, "scale_y", e.mapping.scale_y);
  for (const auto& p : parts) {
    if (!p.is_object()) return makeError(FilmstripErrc::kDamaged, "a part is not an object");
    StoredPart part;
    number(p, "type", part.type);
    number(p, "x", part.x);
    number(p, "y", part.y);
    number(p, "angle_deg", part.angle_deg);
    number(p, "score", part.score);
    number(p, "offered", part.offered);
    e.parts.push_back(part);
  }
  if (bad) return *bad;
  if (!(e.mapping.scale_x > 0) || !(e.mapping.scale_y > 0))
    return makeError(FilmstripErrc::kDamaged, "\"mapping\" has a scale that is not positive");
  if (!e.reply_frame.empty() && !results::isReplyFrameName(e.reply_frame))
    return makeError(FilmstripErrc::kDamaged, "\"reply_frame\" names no frame");
  // The image is a file of the filmstrip's directory, never a path.
  if (!e.image.empty() && (e.image.find('/') != std::string::npos || e.image[0] == '.'))
    return makeError(FilmstripErrc::kDamaged, "\"image\" is not a file name");
  return e;
}

}  // namespace picksight::filmstrip
