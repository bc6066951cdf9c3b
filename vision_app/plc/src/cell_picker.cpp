// PLC triggers picked through the cell's one LOCATE path.
#include "picksight/plc/cell_picker.hpp"

#include <chrono>

#include "picksight/protocol/cell_commands.hpp"
#include "picksight/protocol/robot_errors.hpp"
#include "picksight/results/request_record.hpp"

namespace picksight::plc {

uint16_t frameCode(store::CoordinateFrame frame) {
  switch (frame) {
    case store::CoordinateFrame::kVisionPixels:
      return kFrameVisionPixels;
    case store::CoordinateFrame::kVisionMm:
      return kFrameVisionMm;
    case store::CoordinateFrame::kRobot:
      return kFrameRobot;
  }
  return kFrameVisionPixels;
}

PlcResult plcResult(const cell::CellLocate& located) {
  PlcResult result;
  result.frame_sequence = located.outcome.frame.sequence;
  result.frame = frameCode(located.pick.frame);
  result.parts.reserve(located.pick.poses.size());
  for (size_t i = 0; i < located.pick.poses.size(); ++i) {
    const auto& pose = located.pick.poses[i];
    const auto& part = located.outcome.parts[located.pick.parts[i]];
    result.parts.push_back({part.type, pose.x, pose.y, pose.rz_deg, part.score});
  }
  return result;
}

PlcDevice::Picker cellPicker(cell::CellContext& cell, results::ResultsPublisher* const& results,
                             filmstrip::Filmstrip* const& filmstrip) {
  return [&cell, &results, &filmstrip](int type) -> Result<PlcResult> {
    const auto started = std::chrono::steady_clock::now();
    auto located = cell::locateAndPick(cell, type);
    Result<PlcResult> result =
        located ? Result<PlcResult>(plcResult(*located)) : Result<PlcResult>(located.error());
    if (results || filmstrip) {
      // Queued only: the publisher and the filmstrip's writer do their
      // work on their own threads.
      const std::string reply =
          located ? protocol::locateReply(located->pick) : protocol::errorReply(located.error());
      auto frame = located ? located->outcome.pixels : nullptr;
      auto record = results::locateRecord(std::move(located), type, cell.vision.options());
      record->request_line = "PLC TRIGGER " + std::to_string(type);
      record->client = "plc";
      record->reply = reply;
      record->elapsed_ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started)
              .count();
      if (filmstrip) filmstrip->record(filmstrip->reserve(), {record, std::move(frame), "PLC", 0});
      if (results) results->publish(std::move(record));
    }
    return result;
  };
}

PlcDevice::FrameState cellFrameState(const store::CellCalibration& calibration) {
  return [&calibration] {
    const auto geometry = calibration.geometry();
    return geometry ? frameCode(geometry->frame()) : kFrameDamaged;
  };
}

int robotErrorCodeOf(const Error& error) { return protocol::robotErrorCode(error.code); }

PlcDevice::JobLoader cellJobLoader(jobs::JobSwitch& jobs) {
  return [&jobs](uint16_t number) -> Result<void> {
    auto loaded = jobs.loadNumber(number);
    if (!loaded) return loaded.error();
    return {};
  };
}

PlcDevice::JobState cellJobState(const jobs::JobSwitch& jobs) {
  return [&jobs] { return jobs.currentNumber(); };
}

}  // namespace picksight::plc
