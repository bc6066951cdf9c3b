// LOCATE with grasps, LOCATE ALL, WHY, GRASP, GRIPPER, STATUS, EXPOSURE, ROI,
// CAMMODE.
#include "picksight/protocol/cell_commands.hpp"

#include <algorithm>
#include <cctype>

#include "picksight/common/text.hpp"
#include "picksight/results/request_record.hpp"

namespace picksight::protocol {

using cell::CellContext;
using cell::CellLocate;
using cell::CellPick;
using cell::locateAndPick;
using cell::VisionService;
using cell::VisionServiceErrc;

using store::frameName;
using store::GraspSetup;
using store::ModelErrc;
using store::ModelLibrary;
using store::ModelList;
using store::validateGrasp;

namespace {
std::string reply(const Error& e) { return errorReply(e); }

std::string typeError(const std::string& command, const std::string& arg) {
  return errorReply(
      ProtocolErrc::kBadArguments,
      command + ": type must be an integer in [0, 9999], got '" + printable(arg) + "'");
}

bool modelExists(const VisionService& vision, int type) {
  if (!vision.models()) return false;
  const auto models = vision.models()->snapshot();
  return std::any_of(models->begin(), models->end(),
                     [&](const vision::PartModel& m) { return m.type == type; });
}

// LOCATE <type> | LOCATE ALL. The record of what it saw goes to the
// session (for WHY) and, once the reply is sent, to the results stream.
std::string locate(const Request& r, CellContext& cell) {
  if (r.args.size() != 1)
    return errorReply(ProtocolErrc::kBadArguments, "usage: LOCATE <type> | LOCATE ALL");
  const bool all = toUpper(r.args[0]) == "ALL";
  const auto type = all ? std::optional<int>(-1) : parseType(r.args[0]);
  if (!type) return typeError("LOCATE", r.args[0]);
  auto located = locateAndPick(cell, *type);
  const std::string out = !located ? reply(located.error())
                          : all    ? locateAllReply(*located)
                                   : locateReply(located->pick);
  r.session->frame = located ? located->outcome.pixels : nullptr;
  auto record = results::locateRecord(std::move(located), *type, cell.vision.options());
  record->request_line = r.line;
  record->client = r.session->client;
  r.session->last_locate = record;
  r.session->record = std::move(record);
  return out;
}

std::string why(const Request& r) {
  if (!r.args.empty()) return errorReply(ProtocolErrc::kBadArguments, "WHY takes no arguments");
  if (!r.session->last_locate) return "OK 0 no LOCATE yet";
  return r.session->last_locate->why();
}

// GRASP <type> ADD x y rz | CLEAR | LIST, and GRIPPER <type> FINGER x y w h |
// CLEAR | LIST: one editor, the two lists differ in their item.
std::string editGrasp(const Request& r, CellContext& cell, bool gripper) {
  const std::string usage = gripper ? "usage: GRIPPER <type> FINGER <x> <y> <w> <h> | CLEAR | LIST"
                                    : "usage: GRASP <type> ADD <x> <y> <rz> | CLEAR | LIST";
  if (r.args.size() < 2) return errorReply(ProtocolErrc::kBadArguments, usage);
  const auto type = parseType(r.args[0]);
  if (!type) return typeError(gripper ? "GRIPPER" : "GRASP", r.args[0]);
  const std::string action = toUpper(r.args[1]);
  const std::string add_word = gripper ? "FINGER" : "ADD";
  const size_t add_values = gripper ? 4 : 3;
  std::optional<std::vector<double>> values;
  if (action == add_word) {
    values = parseNumbers(r.args, 2);
    if (!values || values->size() != add_values)
      return errorReply(ProtocolErrc::kBadArguments, usage);
  } else if ((action != "CLEAR" && action != "LIST") || r.args.size() != 2) {
    return errorReply(ProtocolErrc::kBadArguments, usage);
  }
  if (!modelExists(cell.vision, *type)) {
    return errorReply(VisionServiceErrc::kUnknownType,
                      "no model for type " + std::to_string(*type) + " (see MODELS, LEARN)");
  }
  ModelLibrary& library = *cell.vision.models();
  std::lock_guard<std::mutex> lock(cell.grasp_edits);
  GraspSetup setup = library.graspOf(*type);
  if (action == "LIST") {
    std::string out;
    if (gripper) {
      out = "OK " + std::to_string(setup.gripper.fingers.size());
      for (const auto& f : setup.gripper.fingers) {
        out += " " + formatFixed(f.x_mm) + " " + formatFixed(f.y_mm) + " " +
               formatFixed(f.width_mm) + " " + formatFixed(f.height_mm);
      }
    } else {
      out = "OK " + std::to_string(setup.styles.size());
      for (const auto& s : setup.styles)
        out += " " + formatFixed(s.x_mm) + " " + formatFixed(s.y_mm) + " " + formatFixed(s.rz_deg);
    }
    return out;
  }
  if (action == "CLEAR") {
    if (gripper) {
      setup.gripper.fingers.clear();
    } else {
      setup.styles.clear();
    }
  } else if (gripper) {
    const auto& v = *values;
    setup.gripper.fingers.push_back({v[0], v[1], v[2], v[3]});
  } else {
    const auto& v = *values;
    setup.styles.push_back({v[0], v[1], v[2]});
  }
  if (auto valid = validateGrasp(setup); !valid)
    return errorReply(ProtocolErrc::kBadArguments, valid.error().message);
  auto ok = library.setGrasp(*type, setup, r.line);
  if (!ok) {
    if (ok.error().code == ModelErrc::kUnknownType)
      return errorReply(VisionServiceErrc::kUnknownType, ok.error().message);
    return errorReply(VisionServiceErrc::kStorageFailed,
                      "cannot store the model: " + ok.error().message);
  }
  const size_t count = gripper ? setup.gripper.fingers.size() : setup.styles.size();
  return "OK " + std::to_string(count);
}

std::string status(const Request& r, CellContext& cell) {
  if (!r.args.empty()) return errorReply(ProtocolErrc::kBadArguments, "STATUS takes no arguments");
  const auto calib = cell.calibration.summary();
  const auto geometry = cell.calibration.geometry();
  const auto models =
      cell.vision.models() ? cell.vision.models()->snapshot() : std::make_shared<const ModelList>();
  const auto last = cell.vision.lastFrame();
  // A damaged calibration file has no frame: frame=none, calibration=damaged.
  std::string out = "OK frame=" + std::string(geometry ? frameName(geometry->frame()) : "none");
  out += " scale=";
  out += calib.scale ? formatFixed(calib.scale->mm_per_px_x, 6) + "x" +
                           formatFixed(calib.scale->mm_per_px_y, 6)
                     : std::string("none");  // 1 unit per pixel
  out += " lens=" + std::string(calib.lens ? "1" : "0");
  out += " points=" + std::to_string(calib.points);
  if (calib.transform) {
    out += " transform=" + formatFixed(calib.transform->transform.dx) + "," +
           formatFixed(calib.transform->transform.dy) + "," +
           formatFixed(calib.transform->transform.rz_deg) +
           " rms=" + formatFixed(calib.transform->rms);
  } else {
    out += " transform=none";
  }
  out += " camera=" + printable(cell.vision.camera(), 64);
  out += " frames=" + std::to_string(cell.vision.framesReceived());
  out += " last_frame=" + (last ? std::to_string(last->sequence) : std::string("none"));
  out += " models=" + std::to_string(models->size());
  out += " locates=" + std::to_string(cell.locates.load());
  out += " offered=" + std::to_string(cell.last_offered.load());
  out += " skipped=" + std::to_string(cell.last_skipped.load());
  out += " skipped_total=" + std::to_string(cell.skipped_total.load());
  out += std::string(" calibration=") + (geometry ? "ok" : "damaged");
  return out;
}

std::string exposure(const Request& r, CellContext& cell) {
  if (r.args.size() > 1)
    return errorReply(ProtocolErrc::kBadArguments, "usage: EXPOSURE [<value>]");
  std::optional<double> value;
  if (!r.args.empty()) {
    value = parseDouble(r.args[0]);
    if (!value || !(*value > 0))
      return errorReply(
          ProtocolErrc::kBadArguments,
          "EXPOSURE: value must be a positive number, got '" + printable(r.args[0]) + "'");
  }
  // The first name the camera knows decides; a camera that knows it but
  // refuses the value explains why better than the names it does not know.
  std::string why;
  for (const auto& name : exposureFeatureNames()) {
    auto answer = cell.vision.withCamera([&](link::CameraLink& camera) {
      return value ? camera.setFeature(name, formatFixed(*value, 3)) : camera.feature(name);
    });
    if (answer) return "OK " + name + " " + printable(*answer, 64);
    const std::error_code code = answer.error().code;
    if (code == link::CameraErrc::kNoVideoServer)
      return errorReply(link::CameraErrc::kNoVideoServer,
                        "video server: " + answer.error().message);
    if (code != link::CameraErrc::kUnknownFeature || why.empty())
      why = printable(answer.error().message, 120);
    if (code != link::CameraErrc::kUnknownFeature) break;
  }
  return errorReply(link::CameraErrc::kCameraRefused, "EXPOSURE: " + why);
}

std::string roi(const Request& r, CellContext& cell) {
  const std::string usage = "usage: ROI <x> <y> <width> <height> | ROI FULL | ROI";
  if (r.args.empty()) {
    auto answer = cell.vision.withCamera([](link::CameraLink& camera) { return camera.roi(); });
    if (!answer) {
      // No video server: ERROR 21, as when a frame is asked for; anything
      // else the camera's refusal.
      Error error = answer.error();
      if (error.code != link::CameraErrc::kNoVideoServer)
        error.code = link::CameraErrc::kCameraRefused;
      error.message = "ROI: " + printable(error.message, 120);
      return errorReply(error);
    }
    // Until a camera first opens, the video server knows neither its
    // sensor's size nor its output's and describes both as 0 x 0: told as
    // the region, a robot took a size the camera does not have (all zeros,
    // in the first moments after a start). It is told to ask again, as for
    // a frame not yet there.
    if (answer->width <= 0 || answer->height <= 0)
      return errorReply(link::CameraErrc::kNoFrame,
                        "ROI: camera " + printable(cell.vision.camera(), 64) +
                            " has not opened yet: its size is not known until it has");
    return "OK " + std::to_string(answer->x) + " " + std::to_string(answer->y) + " " +
           std::to_string(answer->width) + " " + std::to_string(answer->height);
  }
  cv::Rect wanted;  // empty: the full sensor
  if (r.args.size() == 4) {
    int v[4];
    for (size_t i = 0; i < 4; ++i) {
      const auto n = parseInt(r.args[i]);
      if (!n || *n < 0 || *n > 100000 || (i >= 2 && *n == 0))
        return errorReply(ProtocolErrc::kBadArguments, usage);
      v[i] = static_cast<int>(*n);
    }
    wanted = cv::Rect(v[0], v[1], v[2], v[3]);
  } else if (r.args.size() != 1 || toUpper(r.args[0]) != "FULL") {
    return errorReply(ProtocolErrc::kBadArguments, usage);
  }
  auto answer =
      cell.vision.withCamera([&](link::CameraLink& camera) { return camera.setRoi(wanted); });
  if (!answer) {
    const link::CameraErrc code = answer.error().code == link::CameraErrc::kNoVideoServer
                                      ? link::CameraErrc::kNoVideoServer
                                      : link::CameraErrc::kCameraRefused;
    return errorReply(code, "ROI: " + printable(answer.error().message, 120));
  }
  return std::string("OK");
}

std::string cameraModeReply(const link::CameraModeSettings& m) {
  switch (m.mode) {
    case link::CameraMode::kSoftwareTrigger:
      return "OK SOFTWARE";
    case link::CameraMode::kHardwareTrigger:
      return "OK HARDWARE " + printable(m.line, 32) + " " + std::to_string(m.timeout.count());
    case link::CameraMode::kFreeRun:
      break;
  }
  return "OK FREE " + formatFixed(m.fps, 3);
}

// CAMMODE [FREE [<fps>] | SOFTWARE | HARDWARE [<line> [<timeout_ms>]]]: the
// reply is the mode read back from the camera.
std::string cameraMode(const Request& r, CellContext& cell) {
  const std::string usage =
      "usage: CAMMODE [FREE [<fps>] | SOFTWARE | HARDWARE [<line> [<timeout_ms>]]]";
  std::optional<link::CameraModeSettings> wanted;
  if (!r.args.empty()) {
    link::CameraModeSettings m;
    const std::string kind = toUpper(r.args[0]);
    if (kind == "FREE" && r.args.size() <= 2) {
      m.mode = link::CameraMode::kFreeRun;
      if (r.args.size() == 2) {
        const auto fps = parseDouble(r.args[1]);
        if (!fps || !(*fps > 0 && *fps <= 1000))
          return errorReply(
              ProtocolErrc::kBadArguments,
              "CAMMODE FREE: fps must be in (0, 1000], got '" + printable(r.args[1]) + "'");
        m.fps = *fps;
      }
    } else if (kind == "SOFTWARE" && r.args.size() == 1) {
      m.mode = link::CameraMode::kSoftwareTrigger;
    } else if (kind == "HARDWARE" && r.args.size() <= 3) {
      m.mode = link::CameraMode::kHardwareTrigger;
      if (r.args.size() >= 2) {
        const std::string& line = r.args[1];
        const bool name_ok = line.size() <= 32 && std::all_of(line.begin(), line.end(), [](char c) {
                               return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
                             });
        if (!name_ok)
          return errorReply(ProtocolErrc::kBadArguments,
                            "CAMMODE HARDWARE: line must be 1 to 32 of A-Z a-z 0-9 _, got '" +
                                printable(line) + "'");
        m.line = line;
      }
      if (r.args.size() == 3) {
        const auto ms = parseInt(r.args[2]);
        if (!ms || *ms < 1 || *ms > 3600000)
          return errorReply(ProtocolErrc::kBadArguments,
                            "CAMMODE HARDWARE: timeout_ms must be in [1, 3600000], got '" +
                                printable(r.args[2]) + "'");
        m.timeout = std::chrono::milliseconds(*ms);
      }
    } else {
      return errorReply(ProtocolErrc::kBadArguments, usage);
    }
    wanted = m;
  }
  auto answer =
      cell.vision.withCamera([&](link::CameraLink& camera) -> Result<link::CameraModeSettings> {
        if (wanted) {
          if (auto set = camera.setMode(*wanted); !set) return set.error();
        }
        return camera.mode();
      });
  if (!answer) {
    const link::CameraErrc code = answer.error().code == link::CameraErrc::kNoVideoServer
                                      ? link::CameraErrc::kNoVideoServer
                                      : link::CameraErrc::kCameraRefused;
    return errorReply(code, "CAMMODE: " + printable(answer.error().message, 160));
  }
  return cameraModeReply(*answer);
}
}  // namespace

std::string locateReply(const CellPick& pick) {
  std::string out = "OK " + std::to_string(pick.poses.size());
  for (const auto& p : pick.poses)
    out += " " + formatFixed(p.x) + " " + formatFixed(p.y) + " " + formatFixed(p.rz_deg);
  return out;
}

std::string locateAllReply(const CellLocate& located) {
  const CellPick& pick = located.pick;
  std::string out = "OK " + std::to_string(pick.poses.size());
  for (size_t i = 0; i < pick.poses.size(); ++i) {
    const auto& p = pick.poses[i];
    out += " " + std::to_string(located.outcome.parts[pick.parts[i]].type) + " " +
           formatFixed(p.x) + " " + formatFixed(p.y) + " " + formatFixed(p.rz_deg);
  }
  return out;
}

const std::vector<std::string>& exposureFeatureNames() {
  static const std::vector<std::string> names{"ExposureTime", "ExposureTimeAbs",
                                              "exposure_time_absolute"};
  return names;
}

void addCellCommands(CommandTable& table, CellContext& cell) {
  table.add(
      "LOCATE", "LOCATE <type> | LOCATE ALL", [&cell](const Request& r) { return locate(r, cell); },
      neverChanges, Publishes::kRecord);
  table.add("WHY", "WHY", why, neverChanges);
  table.add(
      "GRASP", "GRASP <type> ADD <x> <y> <rz> | CLEAR | LIST",
      [&cell](const Request& r) { return editGrasp(r, cell, false); }, changesUnlessList);
  table.add(
      "GRIPPER", "GRIPPER <type> FINGER <x> <y> <w> <h> | CLEAR | LIST",
      [&cell](const Request& r) { return editGrasp(r, cell, true); }, changesUnlessList);
  table.add(
      "STATUS", "STATUS", [&cell](const Request& r) { return status(r, cell); }, neverChanges);
  table.add(
      "EXPOSURE", "EXPOSURE [<value>]", [&cell](const Request& r) { return exposure(r, cell); },
      changesWithArguments);
  table.add(
      "ROI", "ROI [<x> <y> <w> <h> | FULL]", [&cell](const Request& r) { return roi(r, cell); },
      changesWithArguments);
  table.add(
      "CAMMODE", "CAMMODE [FREE [<fps>] | SOFTWARE | HARDWARE [<line> [<timeout_ms>]]]",
      [&cell](const Request& r) { return cameraMode(r, cell); }, changesWithArguments);
}

}  // namespace picksight::protocol
