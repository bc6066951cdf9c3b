// Vision cell wiring.
#include "picksight/app/vision_cell.hpp"

#include <chrono>

#include "picksight/protocol/calibration_commands.hpp"
#include "picksight/protocol/filmstrip_commands.hpp"
#include "picksight/protocol/job_commands.hpp"
#include "picksight/protocol/model_commands.hpp"
#include "picksight/protocol/vision_settings_commands.hpp"

namespace picksight::app {

using protocol::addCalibrationCommands;
using protocol::addCellCommands;
using protocol::addModelCommands;
using protocol::addVisionSettingsCommands;
using protocol::Publishes;
using protocol::Session;

using cell::VisionOptions;

VisionCell::VisionCell(const std::string& data_dir, std::unique_ptr<link::CameraLink> camera,
                       VisionOptions options, std::vector<std::string> command_line_settings)
    : settings_file_(data_dir + "/vision.json"),
      command_line_settings_(std::move(command_line_settings)),
      models_(data_dir + "/models"),
      calibration_(data_dir + "/calibration.yaml"),
      vision_(std::move(camera), std::move(options), &models_),
      protocol_(vision_),
      context_(vision_, calibration_),
      jobs_(data_dir + "/jobs", context_, models_) {
  // What each command publishes is in its table entry (Publishes).
  addModelCommands(protocol_.table(), vision_);
  addCalibrationCommands(protocol_.table(), vision_, calibration_);
  addCellCommands(protocol_.table(), context_);
  addVisionSettingsCommands(protocol_.table(), vision_);
  protocol::addJobCommands(protocol_.table(), jobs_);
  protocol::addFilmstripCommands(protocol_.table(), context_, filmstrip_);
}

std::vector<std::string> VisionCell::load() {
  std::vector<std::string> problems;
  if (auto ok = vision_.loadSettings(settings_file_, command_line_settings_); !ok)
    problems.push_back(
        "vision settings rejected (LOCATE, LEARN and VISION changes refused until repaired, or "
        "VISION RESET): " +
        ok.error().message);
  for (auto& p : jobs_.clean()) problems.push_back("jobs: " + p);
  for (auto& p : models_.load()) problems.push_back("model rejected: " + p);
  for (auto& p : models_.checkHistory()) problems.push_back("undo history: " + p);
  if (auto ok = calibration_.load(); !ok)
    problems.push_back(
        "calibration rejected (LOCATE and changes refused until repaired, or CLEARCAL): " +
        ok.error().message);
  if (auto resumed = jobs_.resume()) problems.push_back("jobs: " + *resumed);
  return problems;
}

Result<std::vector<std::string>> VisionCell::openFilmstrip(filmstrip::FilmstripOptions options) {
  auto strip = filmstrip::Filmstrip::open(std::move(options));
  if (!strip) return strip.error();
  filmstrip_owner_ = std::move(*strip);
  filmstrip_ = filmstrip_owner_.get();
  return filmstrip_->problems();
}

std::function<void(const std::string& reply)> filmstripWhenSent(
    filmstrip::Filmstrip* strip, std::string_view line, Session& s,
    std::shared_ptr<const results::RequestRecord> record) {
  const bool locate = s.command == "LOCATE" && record;
  if (!strip || (!locate && s.command != "WHY")) return nullptr;
  const uint64_t id = strip->reserve();
  if (locate) {
    s.last_locate_entry = id;
    filmstrip::Take take{std::move(record), std::move(s.frame), "LOCATE", 0};
    return [strip, id, take = std::move(take)](const std::string&) mutable {
      strip->record(id, std::move(take));
    };
  }
  // WHY has no record of its own: one with its line and reply, for the
  // entry; its frame is the LOCATE's it explains.
  return [strip, id, line = std::string(line), client = s.client,
          explains = s.last_locate_entry](const std::string& reply) {
    auto why = std::make_shared<results::RequestRecord>();
    why->request = "WHY";
    why->request_line = line;
    why->client = client;
    why->reply = reply;
    strip->record(id, {std::move(why), nullptr, "WHY", explains});
  };
}

}  // namespace picksight::app

namespace picksight::app {

std::string VisionCell::handle(std::string_view line, bool read_only, Session* session) const {
  Session local;
  Session& s = session ? *session : local;
  if (!session) s.received = std::chrono::steady_clock::now();
  const auto frame_before = results_ ? vision_.lastFramePixels() : nullptr;
  std::string reply = protocol_.handle(line, read_only, &s);
  // After the results stream's (which fills in the LOCATE record's reply).
  auto film = filmstripWhenSent(filmstrip_, line, s, s.record);
  if (s.publishes == Publishes::kRecord && s.record) {
    // Filled in (reply, time) even with no results stream: WHY keeps it.
    s.after_reply = results::publishWhenSent(std::move(s.record), s.received, results_);
  } else if ((s.publishes == Publishes::kFrame || s.changed) && results_) {
    auto record = std::make_shared<results::RequestRecord>();
    record->request = s.command;
    record->request_line = std::string(line);
    record->client = s.client;
    record->options = vision_.options();
    // A change (TOLERANCE, FORGET, COMPUTE...) is published for the web's
    // audit trail even when it works on no frame.
    record->changed = s.changed;
    // A request refused before it took a frame has none of its own.
    auto frame = s.publishes == Publishes::kFrame ? vision_.lastFramePixels() : nullptr;
    if (frame != frame_before) record->frame = std::move(frame);
    s.after_reply = results::publishWhenSent(std::move(record), s.received, results_);
  }
  if (film) {
    if (s.after_reply) {
      s.after_reply = [publish = std::move(s.after_reply),
                       film = std::move(film)](const std::string& sent) {
        publish(sent);
        film(sent);
      };
    } else {
      s.after_reply = std::move(film);
    }
  }
  s.frame = nullptr;  // no session keeps a frame
  if (!session && s.after_reply) {
    s.after_reply(reply);
    s.after_reply = nullptr;
  }
  return reply;
}

}  // namespace picksight::app
