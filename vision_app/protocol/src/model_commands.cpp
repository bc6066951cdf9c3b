// LEARN, MODELS, FORGET and BLOBS.
#include "picksight/protocol/model_commands.hpp"

#include <cctype>

#include "picksight/common/text.hpp"

namespace picksight::app {

bool validModelName(std::string_view name) {
  if (name.empty() || name.size() > 32) return false;
  for (char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.')
      return false;
  }
  return true;
}

std::string modelSummary(const vision::PartModel& m) {
  return std::to_string(m.type) + " " + m.name + " " + formatFixed(m.body.area) + " " +
         std::to_string(m.body.holes) + " " + formatFixed(m.symmetryDeg());
}

std::string blobSummary(const vision::BlobFeatures& b) {
  std::string s = formatFixed(b.centroid.x) + " " + formatFixed(b.centroid.y) + " " +
                  formatFixed(b.angle_deg) + " " + formatFixed(b.area) + " " +
                  formatFixed(b.perimeter) + " " + formatFixed(b.roundness) + " " +
                  std::to_string(b.holes) + " " + formatFixed(b.eccentricity) + " " +
                  std::to_string(b.bbox.x) + " " + std::to_string(b.bbox.y) + " " +
                  std::to_string(b.bbox.width) + " " + std::to_string(b.bbox.height);
  for (double h : b.log_hu) s += " " + formatFixed(h);
  return s;
}

void addModelCommands(CommandTable& table, VisionService& vision) {
  table.add("LEARN", "LEARN <type> [name]", [&vision](const Request& r) {
    if (r.args.empty() || r.args.size() > 2)
      return errorReply(ProtocolErrc::kBadArguments, "usage: LEARN <type> [name]");
    const auto type = parseType(r.args[0]);
    if (!type) {
      return errorReply(
          ProtocolErrc::kBadArguments,
          "LEARN: type must be an integer in [0, 9999], got '" + printable(r.args[0]) + "'");
    }
    const std::string name = r.args.size() > 1 ? r.args[1] : "type" + std::to_string(*type);
    if (!validModelName(name)) {
      return errorReply(
          ProtocolErrc::kBadArguments,
          "LEARN: name must be 1-32 of A-Z a-z 0-9 _ - ., got '" + printable(name) + "'");
    }
    auto model = vision.learn(*type, name);
    if (!model) return errorReply(model.error());
    return "OK " + modelSummary(*model) + " " + (model->body.mirror_symmetric ? "1" : "0");
  });
  table.add(
      "MODELS", "MODELS",
      [&vision](const Request& r) {
        if (!r.args.empty())
          return errorReply(ProtocolErrc::kBadArguments, "MODELS takes no arguments");
        const auto models =
            vision.models() ? vision.models()->snapshot() : std::make_shared<const ModelList>();
        std::string reply = "OK " + std::to_string(models->size());
        for (const auto& m : *models) reply += " " + modelSummary(m);
        return reply;
      },
      neverChanges);
  table.add("FORGET", "FORGET <type>", [&vision](const Request& r) {
    if (r.args.size() != 1) return errorReply(ProtocolErrc::kBadArguments, "usage: FORGET <type>");
    const auto type = parseType(r.args[0]);
    if (!type) {
      return errorReply(
          ProtocolErrc::kBadArguments,
          "FORGET: type must be an integer in [0, 9999], got '" + printable(r.args[0]) + "'");
    }
    if (!vision.models())
      return errorReply(VisionErrc::kUnknownType, "no model for type " + std::to_string(*type));
    auto removed = vision.models()->remove(*type);
    if (!removed) {
      return errorReply(removed.error().code == ModelErrc::kUnknownType
                            ? VisionErrc::kUnknownType
                            : VisionErrc::kStorageFailed,
                        removed.error().message);
    }
    return std::string("OK");
  });
  table.add(
      "BLOBS", "BLOBS",
      [&vision](const Request& r) {
        if (!r.args.empty())
          return errorReply(ProtocolErrc::kBadArguments, "BLOBS takes no arguments");
        auto blobs = vision.blobs();
        if (!blobs) return errorReply(blobs.error());
        std::string reply = "OK " + std::to_string(blobs->size());
        for (const auto& b : *blobs) reply += " " + blobSummary(b);
        return reply;
      },
      neverChanges);
}

}  // namespace picksight::app
