// The cell's LOCATE, one path for the robot port, the PLC port and the
// offline CLI: a frame's parts of a type, each with the first grasp its
// fingers can take (grasp_planner), in the reply frame of the cell's
// calibration. The callers only format what it returns (the robot's reply
// line, the PLC's registers) and publish it.
//
// Threading: locateAndPick may be called from any thread (VisionService
// serializes the camera; the calibration and model library are snapshots).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>

#include "picksight/cell/grasp_planner.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/store/cell_calibration.hpp"
#include "picksight/store/model_library.hpp"

namespace picksight::cell {

// A LOCATE's parts and the grasp poses offered for them.
struct CellLocate {
  LocateOutcome outcome;
  CellPick pick;
  // What the grasps were chosen with, for the results stream.
  std::shared_ptr<const store::GraspMap> grasps;
  std::optional<store::CellGeometry> geometry;
};

// What a cell's requests share: its vision service and calibration
// (borrowed), the LOCATE figures STATUS reports, and the lock GRASP and
// GRIPPER edits take. Owned by VisionCell.
struct CellContext {
  CellContext(VisionService& v, store::CellCalibration& c) : vision(v), calibration(c) {}
  VisionService& vision;
  store::CellCalibration& calibration;
  // LOCATE figures for STATUS.
  std::atomic<uint64_t> locates{0};
  std::atomic<uint64_t> last_offered{0};
  std::atomic<uint64_t> last_skipped{0};  // parts with no free grasp in the last LOCATE
  std::atomic<uint64_t> skipped_total{0};
  std::mutex grasp_edits;  // serializes GRASP/GRIPPER read-modify-writes
};

// The parts `locate` finds, picked with the grasps of `models` (none when
// null) and turned to the reply frame of `calibration`. The calibration is
// checked before `locate` runs (a damaged file is an error, never a silent
// change of frame) and read again after it (a CLEARCAL or a COMPUTE may
// have come meanwhile).
Result<CellLocate> locateAndPick(const store::CellCalibration& calibration,
                                 const store::ModelLibrary* models,
                                 const std::function<Result<LocateOutcome>()>& locate);

// LOCATE of `type` (-1: every trained type) on a fresh frame of the cell's
// camera, counted for STATUS: the robot port's LOCATE and the PLC port's
// trigger, so both give the same poses for the same frame.
Result<CellLocate> locateAndPick(CellContext& cell, int type);

}  // namespace picksight::cell
