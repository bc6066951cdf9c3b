// Robot protocol commands that run the cell: LOCATE and LOCATE ALL (grasp
// poses in the reply frame), WHY, GRASP and GRIPPER (per model), STATUS,
// and the camera settings passed through to the video server (EXPOSURE,
// ROI); docs/PROTOCOL.md.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>

#include "picksight/cell/grasp_planner.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/protocol/command_table.hpp"
#include "picksight/results/request_record.hpp"
#include "picksight/results/results_publisher.hpp"
#include "picksight/store/cell_calibration.hpp"

namespace picksight::app {

// What the cell commands share; owned by VisionCell.
struct CellContext {
  CellContext(VisionService& v, CellCalibration& c) : vision(v), calibration(c) {}
  VisionService& vision;
  CellCalibration& calibration;
  // LOCATE figures for STATUS.
  std::atomic<uint64_t> locates{0};
  std::atomic<uint64_t> last_offered{0};
  std::atomic<uint64_t> last_skipped{0};  // parts with no free grasp in the last LOCATE
  std::atomic<uint64_t> skipped_total{0};
  std::mutex grasp_edits;  // serializes GRASP/GRIPPER read-modify-writes
  // Where requests publish what they saw (null: no results stream). Set
  // before serving starts.
  ResultsPublisher* results = nullptr;
};

// A LOCATE's parts and the grasp poses offered for them.
struct CellLocate {
  LocateOutcome outcome;
  CellPick pick;
  // What the grasps were chosen with, for the results stream.
  std::shared_ptr<const GraspMap> grasps;
  std::optional<CellGeometry> geometry;
};

// LOCATE of `type` (-1: every trained type) with grasps in the reply frame,
// counted for STATUS: the one path behind the robot port's LOCATE and the
// PLC port's trigger, so both give the same poses for the same frame.
Result<CellLocate> locateAndPick(CellContext& cell, int type);

// The LOCATE ALL reply: "OK <n>" then type x y rz of each pose.
std::string locateAllReply(const CellLocate& located);

// A LOCATE's results record (the outcome moved in; `located` may be an
// error), with the reply and time to be filled in by the caller.
std::shared_ptr<RequestRecord> locateRecord(Result<CellLocate>&& located, int type,
                                            const VisionOptions& options);

// The camera feature names EXPOSURE tries, in order: GenICam SFNC, older
// GenICam cameras, V4L2.
const std::vector<std::string>& exposureFeatureNames();

// Registers the commands; `context` outlives `table`.
void addCellCommands(CommandTable& table, CellContext& context);

}  // namespace picksight::app
