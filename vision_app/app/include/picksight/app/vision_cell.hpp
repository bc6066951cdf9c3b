// One robot cell's vision: the model library and calibration of a data
// directory, the vision service over a camera link, and the complete robot
// protocol command table. main.cpp, the fuzzer and the tests all build the
// protocol through this class, so they serve the same commands.
//
// Threading: handle() is thread-safe once load() returned.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "picksight/cell/cell_locate.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/filmstrip/filmstrip.hpp"
#include "picksight/jobs/job_switch.hpp"
#include "picksight/link/camera_link.hpp"
#include "picksight/protocol/cell_commands.hpp"
#include "picksight/protocol/robot_protocol.hpp"
#include "picksight/results/results_publisher.hpp"
#include "picksight/store/cell_calibration.hpp"
#include "picksight/store/model_library.hpp"

namespace picksight::app {

class VisionCell {
 public:
  // Files live in `data_dir` (models/, calibration.yaml, vision.json, jobs/);
  // nothing is read or written before load(). `command_line_settings`: the
  // vision settings keys (vision_settings.hpp) set on the command line, which
  // win over vision.json at start.
  VisionCell(const std::string& data_dir, std::unique_ptr<link::CameraLink> camera,
             cell::VisionOptions options, std::vector<std::string> command_line_settings = {});
  VisionCell(const VisionCell&) = delete;
  VisionCell& operator=(const VisionCell&) = delete;

  // Loads models and calibration; one message per problem. A bad file costs
  // what it holds, never the start.
  std::vector<std::string> load();

  void start() { vision_.start(); }
  void stop() { vision_.stop(); }

  // One request line in, one reply line out.
  // On a read-only port requests that change the cell are refused. With a
  // connection's `session` (RobotServer's), what the request publishes is
  // left in session->after_reply for after the reply; without, it is
  // queued before this returns.
  std::string handle(std::string_view line, bool read_only = false,
                     protocol::Session* session = nullptr) const;

  // Every vision request publishes its result there from now on (null:
  // none); `results` outlives the cell. Call before serving starts.
  void publishResultsTo(results::ResultsPublisher* results) { results_ = results; }
  // Where requests publish (null: nowhere); read at each request.
  results::ResultsPublisher* const& results() const { return results_; }

  // Keeps the frames of LOCATE, LOCATE ALL and WHY requests in a
  // filmstrip from now on (and of PLC triggers, through filmstrip());
  // returns what its directory held that could not be read. Call before
  // serving starts. Without, FILMSTRIP and REPLAY answer ERROR 57.
  Result<std::vector<std::string>> openFilmstrip(filmstrip::FilmstripOptions options);
  filmstrip::Filmstrip* const& filmstrip() const { return filmstrip_; }

  cell::VisionService& vision() { return vision_; }
  store::ModelLibrary& models() { return models_; }
  store::CellCalibration& calibration() { return calibration_; }
  jobs::JobSwitch& jobs() { return jobs_; }
  const cell::CellContext& context() const { return context_; }
  cell::CellContext& context() { return context_; }

 private:
  const std::string settings_file_;
  const std::vector<std::string> command_line_settings_;
  store::ModelLibrary models_;
  store::CellCalibration calibration_;
  cell::VisionService vision_;
  protocol::RobotProtocol protocol_;
  cell::CellContext context_;
  jobs::JobSwitch jobs_;
  results::ResultsPublisher* results_ = nullptr;
  std::unique_ptr<filmstrip::Filmstrip> filmstrip_owner_;
  filmstrip::Filmstrip* filmstrip_ = nullptr;  // filmstrip_owner_'s, for the commands
};

// What to run once a request's reply is sent to keep it in `strip`: a
// LOCATE (its `record` and the session's frame) or a WHY; null for other
// requests or without a filmstrip. Reserves the entry's id at once (the
// session's last_locate_entry for a LOCATE).
std::function<void(const std::string& reply)> filmstripWhenSent(
    filmstrip::Filmstrip* strip, std::string_view line, protocol::Session& session,
    std::shared_ptr<const results::RequestRecord> record);

}  // namespace picksight::app
