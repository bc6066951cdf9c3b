// The filmstrip through a vision app's robot port.
#include "picksight/web/filmstrip_view.hpp"

#include <sodium.h>

#include "picksight/common/text.hpp"
#include "picksight/web/web_errors.hpp"

namespace picksight::web {
namespace {

// The app's reply, or its ERROR line as an error.
Result<std::string> ask(ResultFeed& app, const std::string& line) {
  auto reply = app.command(line);
  if (!reply) return reply.error();
  if (reply->rfind("OK", 0) == 0) return reply;
  const bool missing = reply->rfind("ERROR 55 ", 0) == 0;
  return makeError(missing ? WebErrc::kNotFound : WebErrc::kConflict, *reply);
}

}  // namespace

Result<nlohmann::json> filmstripEntries(ResultFeed& app, size_t count, bool failures_only) {
  auto listed = ask(app, "FILMSTRIP " + std::to_string(count) + (failures_only ? " FAILURES" : ""));
  if (!listed) return listed.error();
  // "OK <k>" then "<id> <request> ok|fail" per entry.
  const auto fields = splitFields(*listed, " ");
  nlohmann::json entries = nlohmann::json::array();
  for (size_t i = 2; i + 2 < fields.size(); i += 3) {
    const std::string id(fields[i]);
    auto shown = app.command("FILMSTRIP SHOW " + id);
    if (!shown) return shown.error();
    if (shown->rfind("OK ", 0) == 0) {
      auto entry = nlohmann::json::parse(shown->substr(3), nullptr, false);
      if (!entry.is_discarded() && entry.is_object()) {
        entries.push_back(std::move(entry));
        continue;
      }
    }
    entries.push_back({{"id", parseInt(id).value_or(0)}, {"error", *shown}});
  }
  return nlohmann::json{{"entries", entries}};
}

Result<std::string> filmstripPng(ResultFeed& app, uint64_t id, int side) {
  auto reply = ask(app, "FILMSTRIP IMAGE " + std::to_string(id) + " " + std::to_string(side));
  if (!reply) return reply.error();
  // "OK <width> <height> <base64 PNG>".
  const auto fields = splitFields(*reply, " ");
  if (fields.size() != 4)
    return makeError(WebErrc::kUnreachable, "FILMSTRIP IMAGE: not an image reply");
  const std::string_view text = fields[3];
  std::string png(text.size() / 4 * 3 + 3, '\0');
  size_t length = 0;
  if (sodium_base642bin(reinterpret_cast<unsigned char*>(png.data()), png.size(), text.data(),
                        text.size(), nullptr, &length, nullptr,
                        sodium_base64_VARIANT_ORIGINAL) != 0)
    return makeError(WebErrc::kUnreachable, "FILMSTRIP IMAGE: not base64");
  png.resize(length);
  return png;
}

}  // namespace picksight::web
