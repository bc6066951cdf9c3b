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
#include <condition_variable>
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

// Many LOCATEs at once, or one job switch alone. Unlike std::shared_mutex
// (glibc's prefers readers), a switch that waits holds back new LOCATEs:
// robots that LOCATE without pause never keep a JOB LOAD waiting.
class JobSwitchGate {
 public:
  void lockShared();
  void unlockShared();
  void lock();
  void unlock();

 private:
  std::mutex mutex_;  // guards the three below
  std::condition_variable changed_;
  int readers_ = 0;
  int waiting_switches_ = 0;
  bool switching_ = false;
};

// RAII: a LOCATE's shared hold of the gate.
class OneJob {
 public:
  explicit OneJob(JobSwitchGate& gate) : gate_(gate) { gate_.lockShared(); }
  ~OneJob() { gate_.unlockShared(); }
  OneJob(const OneJob&) = delete;
  OneJob& operator=(const OneJob&) = delete;

 private:
  JobSwitchGate& gate_;
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
  // A LOCATE holds it shared from its first read of the models to its last
  // of the calibration; JOB LOAD holds it alone while it puts a job's
  // camera settings, models, vision settings and calibration in force, so
  // that no LOCATE sees half of one job and half of another.
  JobSwitchGate job_switch;
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
