// LEARN, MODELS, FORGET and BLOBS.
#include "picksight/protocol/model_commands.hpp"

#include <algorithm>
#include <cctype>
#include <optional>
#include <vector>

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

std::string learnReply(const LearnOutcome& learned) {
  std::string reply =
      "OK " + modelSummary(learned.model) + " " + (learned.model.body.mirror_symmetric ? "1" : "0");
  // Robots read the fields up to the first ';' and may ignore the rest.
  for (const auto& w : learned.warnings) reply += " ; warning: " + w;
  return reply;
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

namespace {
// Bound on LEARN AT's numbers: larger than any sensor, small enough that
// no sum of them overflows.
constexpr int kMaxSensorPx = 65535;

// Four integers from args[first]: x y w h, bounded (see kMaxSensorPx).
std::optional<cv::Rect> parseRect(const std::vector<std::string>& args, size_t first) {
  int v[4];
  for (size_t i = 0; i < 4; ++i) {
    const auto n = parseInt(args[first + i]);
    if (!n || *n < (i < 2 ? 0 : 1) || *n > kMaxSensorPx) return std::nullopt;
    v[i] = static_cast<int>(*n);
  }
  return cv::Rect(v[0], v[1], v[2], v[3]);
}
}  // namespace

void addModelCommands(CommandTable& table, VisionService& vision) {
  table.add("LEARN", "LEARN <type> [name] [AT <x> <y> <w> <h>]", [&vision](const Request& r) {
    constexpr const char* kUsage = "usage: LEARN <type> [name] [AT <x> <y> <w> <h>]";
    // "AT" and its four numbers close the line; a name comes before them.
    std::vector<std::string> args = r.args;
    std::optional<cv::Rect> at;
    const auto keyword = std::find(args.begin(), args.end(), "AT");
    if (keyword != args.end()) {
      if (args.end() - keyword != 5) {
        return errorReply(ProtocolErrc::kBadArguments, "LEARN: AT needs <x> <y> <w> <h>");
      }
      const auto rect = parseRect(args, static_cast<size_t>(keyword - args.begin()) + 1);
      if (!rect) {
        return errorReply(ProtocolErrc::kBadArguments,
                          "LEARN: AT x y in [0, " + std::to_string(kMaxSensorPx) +
                              "], w h in [1, " + std::to_string(kMaxSensorPx) + "] sensor pixels");
      }
      at = rect;
      args.erase(keyword, args.end());
    }
    if (args.empty() || args.size() > 2) return errorReply(ProtocolErrc::kBadArguments, kUsage);
    const auto type = parseType(args[0]);
    if (!type) {
      return errorReply(
          ProtocolErrc::kBadArguments,
          "LEARN: type must be an integer in [0, 9999], got '" + printable(args[0]) + "'");
    }
    const std::string name = args.size() > 1 ? args[1] : "type" + std::to_string(*type);
    if (!validModelName(name)) {
      return errorReply(
          ProtocolErrc::kBadArguments,
          "LEARN: name must be 1-32 of A-Z a-z 0-9 _ - ., got '" + printable(name) + "'");
    }
    auto learned = vision.learn(*type, name, at);
    if (!learned) return errorReply(learned.error());
    return learnReply(*learned);
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
