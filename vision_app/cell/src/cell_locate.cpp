// The cell's LOCATE: parts, grasps, reply frame, and the STATUS figures.
#include "picksight/cell/cell_locate.hpp"

namespace picksight::cell {

using store::CellCalibration;
using store::GraspMap;
using store::ModelLibrary;

void JobSwitchGate::lockShared() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return !switching_ && waiting_switches_ == 0; });
  ++readers_;
}

void JobSwitchGate::unlockShared() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (--readers_ == 0) changed_.notify_all();
}

void JobSwitchGate::lock() {
  std::unique_lock<std::mutex> lock(mutex_);
  ++waiting_switches_;
  changed_.wait(lock, [this] { return !switching_ && readers_ == 0; });
  --waiting_switches_;
  switching_ = true;
}

void JobSwitchGate::unlock() {
  std::lock_guard<std::mutex> lock(mutex_);
  switching_ = false;
  changed_.notify_all();
}

Result<CellLocate> locateAndPick(const CellCalibration& calibration, const ModelLibrary* models,
                                 const std::function<Result<LocateOutcome>()>& locate) {
  if (auto geometry = calibration.geometry(); !geometry) return geometry.error();
  auto outcome = locate();
  if (!outcome) return outcome.error();
  // Taken again: a CLEARCAL or a COMPUTE may have come meanwhile.
  const auto geometry = calibration.geometry();
  if (!geometry) return geometry.error();
  const auto grasps = models ? models->grasps() : std::make_shared<const GraspMap>();
  CellLocate located;
  located.pick = pickPoses(*outcome, *grasps, *geometry);
  located.outcome = std::move(*outcome);
  located.grasps = grasps;
  located.geometry = *geometry;
  return located;
}

Result<CellLocate> locateAndPick(CellContext& cell, int type) {
  const OneJob one_job(cell.job_switch);
  auto located = locateAndPick(cell.calibration, cell.vision.models(),
                               [&] { return cell.vision.locate(type); });
  if (!located) return located;
  ++cell.locates;
  cell.last_offered = located->pick.poses.size();
  cell.last_skipped = located->pick.skipped;
  cell.skipped_total += located->pick.skipped;
  return located;
}

}  // namespace picksight::cell
