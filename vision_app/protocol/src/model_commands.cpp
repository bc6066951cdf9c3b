// LEARN, LEARNVIEW, MODELS, TOLERANCE, FORGET, UNDO and BLOBS.
#include "picksight/protocol/model_commands.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <vector>

#include "picksight/common/text.hpp"
#include "picksight/results/request_record.hpp"

namespace picksight::protocol {

using cell::CellLocate;
using cell::LearnOutcome;
using cell::LocateOutcome;
using cell::TryLearnOutcome;
using cell::VisionService;
using cell::VisionServiceErrc;

using store::ModelErrc;
using store::ModelList;
using store::UndoOutcome;

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

std::string learnViewReply(const cell::ViewOutcome& view) {
  const vision::PartModel& m = view.model;
  return "OK " + std::to_string(m.type) + " " + m.name + " " + std::to_string(m.views.size() + 1) +
         " " + formatFixed(m.origin_shift.x) + " " + formatFixed(m.origin_shift.y) + " " +
         formatFixed(view.spread_px) + " ; note: this view read the centroid at " +
         formatFixed(view.reading.x) + " " + formatFixed(view.reading.y) + "; the origin moved " +
         formatFixed(cv::norm(view.moved)) + " px";
}

std::string learnReply(const LearnOutcome& learned) {
  std::string reply =
      "OK " + modelSummary(learned.model) + " " + (learned.model.body.mirror_symmetric ? "1" : "0");
  // Robots read the fields up to the first ';' and may ignore the rest.
  for (const auto& w : learned.warnings) reply += " ; warning: " + w;
  for (const auto& n : learned.notes) reply += " ; note: " + n;
  return reply;
}

std::string tryLearnReply(const TryLearnOutcome& tried) {
  const auto& m = tried.learned.model;
  std::string reply = "OK " + modelSummary(m) + " " + (m.body.mirror_symmetric ? "1" : "0") + " " +
                      std::to_string(tried.found) + " " +
                      std::to_string(tried.located.parts.size());
  for (const auto& w : tried.learned.warnings) reply += " ; warning: " + w;
  for (const auto& n : tried.learned.notes) reply += " ; note: " + n;
  return reply + " ; note: nothing stored";
}

std::string undoReply(const UndoOutcome& undone) {
  const std::string type = std::to_string(undone.type);
  return "OK " + type + (undone.restored ? " restored " : " removed ") +
         std::to_string(undone.left) + " ; undid: " + printable(undone.change, 200) + " ; " +
         (undone.restored ? "type " + type + " is " + modelSummary(*undone.restored) + " again"
                          : "type " + type + " has no model again");
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

// A tolerance TOLERANCE reads and sets: its name in the model file
// (docs/PROTOCOL.md, "Part models"), its bounds and where it lives. Each
// bound is one validateModel accepts, or tighter: past it a value is a typo.
// The hole count is left out: it is a measured feature, not a tolerance,
// and the touching-parts search does not test it, so a changed count would
// not keep a part from being found.
struct ToleranceKey {
  const char* name;
  double low;
  double high;
  bool low_open;   // low itself refused
  bool high_open;  // high itself refused
  bool whole;      // an integer (a yes/no)
  int decimals;    // in replies
  double (*get)(const vision::PartModel&);
  void (*set)(vision::PartModel&, double);
};

const ToleranceKey kToleranceKeys[] = {
    {"area_tolerance", 0, 1, true, true, false, 6,
     [](const vision::PartModel& m) { return m.body.area_tolerance; },
     [](vision::PartModel& m, double v) { m.body.area_tolerance = v; }},
    {"hu_tolerance", 0, 100, true, false, false, 6,
     [](const vision::PartModel& m) { return m.body.hu_tolerance; },
     [](vision::PartModel& m, double v) { m.body.hu_tolerance = v; }},
    {"verify_percent", 0, 100, true, false, false, 3,
     [](const vision::PartModel& m) { return m.verify_percent; },
     [](vision::PartModel& m, double v) { m.verify_percent = v; }},
    {"edge_tolerance_px", 0, 50, true, false, false, 3,
     [](const vision::PartModel& m) { return m.edge_tolerance; },
     [](vision::PartModel& m, double v) { m.edge_tolerance = v; }},
    {"mirror_symmetric", 0, 1, false, false, true, 0,
     [](const vision::PartModel& m) { return m.body.mirror_symmetric ? 1.0 : 0.0; },
     [](vision::PartModel& m, double v) { m.body.mirror_symmetric = v != 0; }},
};

// Any case: robot programs often send upper case only.
const ToleranceKey* findToleranceKey(std::string_view name) {
  for (const auto& key : kToleranceKeys) {
    if (toUpper(name) == toUpper(key.name)) return &key;
  }
  return nullptr;
}

std::string toleranceNames() {
  std::string names;
  for (const auto& key : kToleranceKeys)
    names += (names.empty() ? "" : ", ") + std::string(key.name);
  return names;
}

// "<name> must be ... in (low, high]": the key and its bounds, for errors.
std::string toleranceBounds(const ToleranceKey& key) {
  return std::string(key.name) + " must be " + (key.whole ? "an integer" : "a number") + " in " +
         (key.low_open ? "(" : "[") + formatFixed(key.low, 0) + ", " + formatFixed(key.high, 0) +
         (key.high_open ? ")" : "]");
}

// The value for `key` from `text`, or the error reply naming the key.
Result<double> toleranceValue(const ToleranceKey& key, const std::string& text) {
  const auto bad = [&] {
    return makeError(ProtocolErrc::kBadArguments,
                     "TOLERANCE: " + toleranceBounds(key) + ", got '" + printable(text) + "'");
  };
  std::optional<double> value;
  if (key.whole) {
    if (const auto n = parseInt(text)) value = static_cast<double>(*n);
  } else {
    value = parseDouble(text);
  }
  if (!value || !std::isfinite(*value)) return bad();
  const double v = *value;
  if (v < key.low || v > key.high || (key.low_open && v == key.low) ||
      (key.high_open && v == key.high))
    return bad();
  return v;
}
}  // namespace

std::string toleranceReply(const vision::PartModel& m) {
  std::string reply = "OK " + std::to_string(m.type) + " " + m.name;
  for (const auto& key : kToleranceKeys)
    reply += " " + std::string(key.name) + "=" + formatFixed(key.get(m), key.decimals);
  return reply;
}

namespace {
// LEARN's and TRYLEARN's arguments: <type> [name] [AT <x> <y> <w> <h>].
struct LearnArgs {
  int type = 0;
  std::string name;
  std::optional<cv::Rect> at;
};

Result<LearnArgs> parseLearnArgs(const std::string& word, const Request& r) {
  const std::string usage = "usage: " + word + " <type> [name] [AT <x> <y> <w> <h>]";
  const auto bad = [](const std::string& text) {
    return makeError(ProtocolErrc::kBadArguments, text);
  };
  // "AT" and its four numbers close the line; a name comes before them.
  std::vector<std::string> args = r.args;
  LearnArgs out;
  const auto keyword = std::find_if(args.begin(), args.end(),
                                    [](const std::string& a) { return toUpper(a) == "AT"; });
  if (keyword != args.end()) {
    if (args.end() - keyword != 5) return bad(word + ": AT needs <x> <y> <w> <h>");
    const auto rect = parseRect(args, static_cast<size_t>(keyword - args.begin()) + 1);
    if (!rect) {
      return bad(word + ": AT x y in [0, " + std::to_string(kMaxSensorPx) + "], w h in [1, " +
                 std::to_string(kMaxSensorPx) + "] sensor pixels");
    }
    out.at = rect;
    args.erase(keyword, args.end());
  }
  if (args.empty()) return bad(usage);
  if (args.size() > 2) {
    // "LEARN 1 my part": a name of several words, the commonest slip.
    std::string words;
    std::string joined;
    for (size_t i = 1; i < args.size(); ++i) {
      words += (i > 1 ? " " : "") + args[i];
      joined += (i > 1 ? "_" : "") + args[i];
    }
    return bad(word +
               ": the name is one word (1-32 of A-Z a-z 0-9 _ - ., no spaces or commas), got " +
               std::to_string(args.size() - 1) + " words '" + printable(words) + "': write it as " +
               word + " " + printable(args[0], 8) + " " + printable(joined) +
               (out.at ? " AT <x> <y> <w> <h>" : "") + " (" + usage + ")");
  }
  const auto type = parseType(args[0]);
  if (!type) {
    return bad(word + ": type must be an integer in [0, 9999], got '" + printable(args[0]) + "'");
  }
  out.type = *type;
  out.name = args.size() > 1 ? args[1] : "type" + std::to_string(*type);
  if (!validModelName(out.name)) {
    std::string why =
        out.name.size() > 32 ? std::to_string(out.name.size()) + " characters" : std::string();
    for (char c : out.name) {
      if (why.empty() && !validModelName(std::string(1, c)))
        why = "'" + printable(std::string(1, c)) + "'";
    }
    return bad(word + ": name must be 1-32 of A-Z a-z 0-9 _ - ., got '" + printable(out.name) +
               "' (" + why + ")");
  }
  return out;
}

// The parts a teaching request found (LEARNVIEW's view, TRYLEARN's trial)
// go to the results stream as a LOCATE's would, so that the overlay draws
// the model's outline on each; not kept for WHY, which explains the last
// real LOCATE.
void publishAsLocate(VisionService& vision, const Request& r, const char* request, int type,
                     LocateOutcome&& outcome) {
  CellLocate located;
  located.outcome = std::move(outcome);
  auto record = results::locateRecord(std::move(located), type, vision.options());
  record->request = request;
  record->request_line = r.line;
  record->client = r.session->client;
  r.session->record = std::move(record);
}

// LEARNVIEW <type> [AT <x> <y> <w> <h>] and its reply.
std::string learnView(VisionService& vision, const Request& r) {
  constexpr const char* kUsage = "usage: LEARNVIEW <type> [AT <x> <y> <w> <h>]";
  if (r.args.size() != 1 && r.args.size() != 6)
    return errorReply(ProtocolErrc::kBadArguments, kUsage);
  const auto type = parseType(r.args[0]);
  if (!type) {
    return errorReply(
        ProtocolErrc::kBadArguments,
        "LEARNVIEW: type must be an integer in [0, 9999], got '" + printable(r.args[0]) + "'");
  }
  std::optional<cv::Rect> at;
  if (r.args.size() == 6) {
    if (toUpper(r.args[1]) != "AT") return errorReply(ProtocolErrc::kBadArguments, kUsage);
    at = parseRect(r.args, 2);
    if (!at) {
      return errorReply(ProtocolErrc::kBadArguments,
                        "LEARNVIEW: AT x y in [0, " + std::to_string(kMaxSensorPx) +
                            "], w h in [1, " + std::to_string(kMaxSensorPx) + "] sensor pixels");
    }
  }
  auto view = vision.learnView(*type, at, r.line);
  if (!view) return errorReply(view.error());
  publishAsLocate(vision, r, "LEARNVIEW", *type, std::move(view->located));
  return learnViewReply(*view);
}

std::string tolerance(VisionService& vision, const Request& r) {
  constexpr const char* kUsage = "usage: TOLERANCE <type> [<key> <value>]...";
  if (r.args.empty() || r.args.size() % 2 == 0)
    return errorReply(ProtocolErrc::kBadArguments, kUsage);
  const auto type = parseType(r.args[0]);
  if (!type) {
    return errorReply(
        ProtocolErrc::kBadArguments,
        "TOLERANCE: type must be an integer in [0, 9999], got '" + printable(r.args[0]) + "'");
  }
  // Every pair is checked before the model is touched: a bad one changes
  // nothing.
  std::vector<std::pair<const ToleranceKey*, double>> changes;
  for (size_t i = 1; i < r.args.size(); i += 2) {
    const ToleranceKey* key = findToleranceKey(r.args[i]);
    if (!key) {
      return errorReply(ProtocolErrc::kBadArguments, "TOLERANCE: no key '" + printable(r.args[i]) +
                                                         "' (keys: " + toleranceNames() + ")");
    }
    for (const auto& [seen, unused] : changes) {
      if (seen == key)
        return errorReply(ProtocolErrc::kBadArguments,
                          "TOLERANCE: " + std::string(key->name) + " given twice");
    }
    auto value = toleranceValue(*key, r.args[i + 1]);
    if (!value) return errorReply(value.error());
    changes.emplace_back(key, *value);
  }
  const auto no_model = [&] {
    return errorReply(VisionServiceErrc::kUnknownType,
                      "no model for type " + std::to_string(*type));
  };
  if (!vision.models()) return no_model();
  if (changes.empty()) {
    const auto models = vision.models()->snapshot();
    for (const auto& m : *models) {
      if (m.type == *type) return toleranceReply(m);
    }
    return no_model();
  }
  auto updated = vision.models()->update(
      *type,
      [&](vision::PartModel& m) {
        for (const auto& [key, value] : changes) key->set(m, value);
      },
      r.line);
  if (!updated) {
    // The bounds above are validateModel's or tighter: an invalid model
    // here would be a bug, reported as such rather than as a bad request.
    if (updated.error().code == ModelErrc::kInvalidModel)
      return errorReply(ProtocolErrc::kInternalError, "TOLERANCE: " + updated.error().message);
    return errorReply(updated.error());
  }
  return toleranceReply(*updated);
}
}  // namespace

void addModelCommands(CommandTable& table, VisionService& vision) {
  table.add(
      "LEARN", "LEARN <type> [name] [AT <x> <y> <w> <h>]",
      [&vision](const Request& r) {
        auto args = parseLearnArgs("LEARN", r);
        if (!args) return errorReply(args.error());
        auto learned = vision.learn(args->type, args->name, args->at, r.line);
        if (!learned) return errorReply(learned.error());
        return learnReply(*learned);
      },
      alwaysChanges, Publishes::kFrame);
  table.add(
      "LEARNVIEW", "LEARNVIEW <type> [AT <x> <y> <w> <h>]",
      [&vision](const Request& r) { return learnView(vision, r); }, alwaysChanges,
      Publishes::kRecord);
  table.add(
      "TRYLEARN", "TRYLEARN <type> [name] [AT <x> <y> <w> <h>]",
      [&vision](const Request& r) {
        auto args = parseLearnArgs("TRYLEARN", r);
        if (!args) return errorReply(args.error());
        auto tried = vision.tryLearn(args->type, args->name, args->at);
        if (!tried) return errorReply(tried.error());
        const std::string reply = tryLearnReply(*tried);
        publishAsLocate(vision, r, "TRYLEARN", -1, std::move(tried->located));
        return reply;
      },
      neverChanges, Publishes::kRecord);
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
  table.add(
      "TOLERANCE", "TOLERANCE <type> [<key> <value>]...",
      [&vision](const Request& r) { return tolerance(vision, r); },
      [](const Request& r) { return r.args.size() > 1; });
  table.add("FORGET", "FORGET <type>", [&vision](const Request& r) {
    if (r.args.size() != 1) return errorReply(ProtocolErrc::kBadArguments, "usage: FORGET <type>");
    const auto type = parseType(r.args[0]);
    if (!type) {
      return errorReply(
          ProtocolErrc::kBadArguments,
          "FORGET: type must be an integer in [0, 9999], got '" + printable(r.args[0]) + "'");
    }
    if (!vision.models())
      return errorReply(VisionServiceErrc::kUnknownType,
                        "no model for type " + std::to_string(*type));
    auto removed = vision.models()->remove(*type, r.line);
    if (!removed) {
      return errorReply(removed.error().code == ModelErrc::kUnknownType
                            ? VisionServiceErrc::kUnknownType
                            : VisionServiceErrc::kStorageFailed,
                        removed.error().message);
    }
    return std::string("OK");
  });
  table.add("UNDO", "UNDO", [&vision](const Request& r) {
    if (!r.args.empty()) return errorReply(ProtocolErrc::kBadArguments, "UNDO takes no arguments");
    if (!vision.models())
      return errorReply(ModelErrc::kNothingToUndo, "nothing to undo (no model library)");
    auto undone = vision.models()->undo();
    if (!undone) return errorReply(undone.error());
    return undoReply(*undone);
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
      neverChanges, Publishes::kFrame);
}

}  // namespace picksight::protocol
