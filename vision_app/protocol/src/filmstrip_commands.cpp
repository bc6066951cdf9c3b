// FILMSTRIP (list, SHOW, IMAGE, EXPORT, STATUS) and REPLAY.
#include "picksight/protocol/filmstrip_commands.hpp"

#include <openssl/evp.h>

#include <algorithm>
#include <cctype>
#include <limits>

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include "picksight/cell/vision_settings.hpp"
#include "picksight/common/text.hpp"
#include "picksight/protocol/cell_commands.hpp"
#include "picksight/results/request_record.hpp"

namespace picksight::protocol {

using cell::CellContext;
using filmstrip::Filmstrip;
using filmstrip::FilmstripErrc;

namespace {

const char* kUsage =
    "usage: FILMSTRIP [<n>] [FAILURES] | FILMSTRIP SHOW <id> | FILMSTRIP IMAGE <id> [<side>] | "
    "FILMSTRIP EXPORT <name> [FAILURES] [<n>] | FILMSTRIP STATUS";

std::string offReply() {
  return errorReply(FilmstripErrc::kOff,
                    "no filmstrip: this vision app records none (--filmstrip-dir none)");
}

// An entry id: 1 to 10 digits, not 0.
std::optional<uint64_t> parseId(const std::string& text) {
  if (text.empty() || text.size() > 10 ||
      !std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return std::nullopt;
  const uint64_t id = std::stoull(text);
  if (id == 0) return std::nullopt;
  return id;
}

std::string idError(const std::string& command, const std::string& arg) {
  return errorReply(ProtocolErrc::kBadArguments,
                    command +
                        ": id must be an entry number of 1 to 10 digits (see FILMSTRIP), got '" +
                        printable(arg) + "'");
}

// FILMSTRIP [<n>] [FAILURES]: "OK <k>" then "<id> <request> ok|fail", newest first.
std::string list(const Request& r, const Filmstrip& strip) {
  size_t n = 10;
  bool failures = false;
  for (const auto& arg : r.args) {
    if (toUpper(arg) == "FAILURES" && !failures) {
      failures = true;
      continue;
    }
    const auto v = parseInt(arg);
    if (!v || *v < 1 || *v > static_cast<int64_t>(kMaxListed))
      return errorReply(ProtocolErrc::kBadArguments, "FILMSTRIP: <n> must be in [1, " +
                                                         std::to_string(kMaxListed) + "], got '" +
                                                         printable(arg) + "' (" + kUsage + ")");
    n = static_cast<size_t>(*v);
  }
  const auto entries = strip.list(n, failures);
  std::string out = "OK " + std::to_string(entries.size());
  for (const auto& e : entries)
    out += " " + std::to_string(e.id) + " " + e.request + (e.failure ? " fail" : " ok");
  return out;
}

std::string base64(const std::vector<uchar>& bytes) {
  std::string out(4 * ((bytes.size() + 2) / 3) + 1, '\0');
  const int n = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()), bytes.data(),
                                static_cast<int>(bytes.size()));
  out.resize(static_cast<size_t>(std::max(n, 0)));
  return out;
}

// FILMSTRIP IMAGE <id> [<side>]: "OK <width> <height> <base64 PNG>", the
// frame shrunk to fit <side> pixels (default 1024) each way.
std::string image(const Request& r, const Filmstrip& strip) {
  if (r.args.size() < 2 || r.args.size() > 3)
    return errorReply(ProtocolErrc::kBadArguments, kUsage);
  const auto id = parseId(r.args[1]);
  if (!id) return idError("FILMSTRIP IMAGE", r.args[1]);
  int side = 1024;
  if (r.args.size() == 3) {
    const auto v = parseInt(r.args[2]);
    if (!v || *v < 16 || *v > kMaxImageSide)
      return errorReply(ProtocolErrc::kBadArguments, "FILMSTRIP IMAGE: <side> must be in [16, " +
                                                         std::to_string(kMaxImageSide) +
                                                         "], got '" + printable(r.args[2]) + "'");
    side = static_cast<int>(*v);
  }
  auto stored = strip.frame(*id);
  if (!stored) return errorReply(stored.error());
  cv::Mat picture = stored->second;
  const double shrink =
      std::min(1.0, static_cast<double>(side) / std::max(picture.cols, picture.rows));
  if (shrink < 1.0) {
    cv::resize(stored->second, picture,
               cv::Size(std::max(1, static_cast<int>(picture.cols * shrink)),
                        std::max(1, static_cast<int>(picture.rows * shrink))),
               0, 0, cv::INTER_AREA);
  }
  std::vector<uchar> png;
  if (!picksight::codecs::imencode(".png", picture, png, {cv::IMWRITE_PNG_COMPRESSION, 1}))
    return errorReply(FilmstripErrc::kDamaged,
                      "the frame of entry " + std::to_string(*id) + " cannot be encoded");
  return "OK " + std::to_string(picture.cols) + " " + std::to_string(picture.rows) + " " +
         base64(png);
}

// An export's name: 1 to 64 of A-Z a-z 0-9 _ - ., not starting with '.'.
bool validExportName(const std::string& name) {
  if (name.empty() || name.size() > 64 || name[0] == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
  });
}

// FILMSTRIP EXPORT <name> [FAILURES] [<n>]: the newest <n> frames (default
// every one) as a dir: camera's folder. "OK <frames> <path>".
std::string exportFrames(const Request& r, const Filmstrip& strip) {
  if (r.args.size() < 2 || r.args.size() > 4)
    return errorReply(ProtocolErrc::kBadArguments, kUsage);
  const std::string& name = r.args[1];
  if (!validExportName(name))
    return errorReply(ProtocolErrc::kBadArguments,
                      "FILMSTRIP EXPORT: name must be 1-64 of A-Z a-z 0-9 _ - . (not starting "
                      "with '.'), got '" +
                          printable(name) + "'");
  bool failures = false;
  size_t n = 1000000;
  for (size_t i = 2; i < r.args.size(); ++i) {
    if (toUpper(r.args[i]) == "FAILURES" && !failures) {
      failures = true;
      continue;
    }
    const auto v = parseInt(r.args[i]);
    if (!v || *v < 1 || *v > 100000)
      return errorReply(
          ProtocolErrc::kBadArguments,
          "FILMSTRIP EXPORT: <n> must be in [1, 100000], got '" + printable(r.args[i]) + "'");
    n = static_cast<size_t>(*v);
  }
  // The newest <n> frames, oldest first; a WHY's frame is its LOCATE's:
  // once is enough for a camera.
  std::vector<uint64_t> ids;
  for (const auto& e : strip.list(std::numeric_limits<size_t>::max(), failures)) {
    if (ids.size() >= n) break;
    if (!e.image.empty() && e.request != "WHY") ids.push_back(e.id);
  }
  std::reverse(ids.begin(), ids.end());
  const std::string path = exportPath(strip, name);
  auto written = strip.exportTo(path, ids);
  if (!written) return errorReply(written.error());
  return "OK " + std::to_string(*written) + " " + path;
}

std::string status(const Filmstrip& strip) {
  const auto f = strip.figures();
  return "OK entries=" + std::to_string(f.entries) + " failures=" + std::to_string(f.failures) +
         " bytes=" + std::to_string(f.bytes) + " recorded=" + std::to_string(f.recorded) +
         " dropped_successes=" + std::to_string(f.dropped_successes) +
         " dropped_failures=" + std::to_string(f.dropped_failures) +
         " sampled_out=" + std::to_string(f.sampled_out) + " evicted=" + std::to_string(f.evicted) +
         " write_errors=" + std::to_string(f.write_errors);
}

std::string filmstripCommand(const Request& r, const Filmstrip* strip) {
  if (!strip) return offReply();
  const std::string sub = r.args.empty() ? "" : toUpper(r.args[0]);
  if (sub == "SHOW") {
    if (r.args.size() != 2) return errorReply(ProtocolErrc::kBadArguments, kUsage);
    const auto id = parseId(r.args[1]);
    if (!id) return idError("FILMSTRIP SHOW", r.args[1]);
    auto e = strip->entry(*id);
    if (!e) return errorReply(e.error());
    return "OK " + filmstrip::entryJson(*e);
  }
  if (sub == "IMAGE") return image(r, *strip);
  if (sub == "EXPORT") return exportFrames(r, *strip);
  if (sub == "STATUS") {
    if (r.args.size() != 1) return errorReply(ProtocolErrc::kBadArguments, kUsage);
    return status(*strip);
  }
  return list(r, *strip);
}

// REPLAY <id> [<type> | ALL]: the stored frame through the models, vision
// settings and calibration in use now; the reply LOCATE (or LOCATE ALL)
// would give. Without a type, the one the recorded request asked for.
std::string replay(const Request& r, CellContext& cell, const Filmstrip* strip) {
  if (!strip) return offReply();
  if (r.args.empty() || r.args.size() > 2)
    return errorReply(ProtocolErrc::kBadArguments, "usage: REPLAY <id> [<type> | ALL]");
  const auto id = parseId(r.args[0]);
  if (!id) return idError("REPLAY", r.args[0]);
  std::optional<int> type;
  if (r.args.size() == 2) {
    type = toUpper(r.args[1]) == "ALL" ? std::optional<int>(-1) : parseType(r.args[1]);
    if (!type)
      return errorReply(ProtocolErrc::kBadArguments,
                        "REPLAY: type must be an integer in [0, 9999] or ALL, got '" +
                            printable(r.args[1]) + "'");
  }
  auto stored = strip->frame(*id);
  if (!stored) return errorReply(stored.error());
  const auto& [entry, picture] = *stored;
  if (!type) type = entry.asked_type;
  if (const auto damage = cell.vision.settingsDamage())
    return errorReply(cell::VisionSettingsErrc::kDamaged, *damage);
  const auto models = cell.vision.models() ? cell.vision.models()->snapshot()
                                           : std::make_shared<const store::ModelList>();
  if (*type >= 0 && !models->empty() &&
      std::none_of(models->begin(), models->end(),
                   [&](const vision::PartModel& m) { return m.type == *type; }))
    return errorReply(cell::VisionServiceErrc::kUnknownType,
                      "no model for type " + std::to_string(*type) + " (see MODELS)");
  Frame frame;
  frame.image = picture;
  frame.mapping = entry.mapping;
  frame.info.camera = entry.camera;
  frame.info.sequence = entry.sequence;
  frame.info.width = static_cast<uint32_t>(picture.cols);
  frame.info.height = static_cast<uint32_t>(picture.rows);
  const auto settings = std::make_shared<const cell::VisionOptions>(cell.vision.options());
  auto located = cell::locateAndPick(
      cell.calibration, cell.vision.models(), [&]() -> Result<cell::LocateOutcome> {
        auto outcome = cell::locateInFrame(frame, *settings, models, *type);
        outcome.settings = settings;
        return outcome;
      });
  const std::string out = !located    ? errorReply(located.error())
                          : *type < 0 ? locateAllReply(*located)
                                      : locateReply(located->pick);
  // Published as a LOCATE's record is (the page draws what it found), but
  // never WHY's: a replay is not the connection's last LOCATE.
  auto record = results::locateRecord(std::move(located), *type, *settings);
  record->request = "REPLAY";
  record->request_line = r.line;
  record->client = r.session->client;
  r.session->record = std::move(record);
  return out;
}

}  // namespace

std::string exportPath(const Filmstrip& strip, const std::string& name) {
  return strip.options().dir + "/exports/" + name;
}

void addFilmstripCommands(CommandTable& table, CellContext& cell, const Filmstrip* const& strip) {
  // Lists and reads change nothing; an export writes a folder of frames.
  table.add(
      "FILMSTRIP", kUsage, [&strip](const Request& r) { return filmstripCommand(r, strip); },
      [](const Request& r) { return !r.args.empty() && toUpper(r.args[0]) == "EXPORT"; });
  table.add(
      "REPLAY", "REPLAY <id> [<type> | ALL]",
      [&cell, &strip](const Request& r) { return replay(r, cell, strip); }, neverChanges,
      Publishes::kRecord);
}

}  // namespace picksight::protocol
