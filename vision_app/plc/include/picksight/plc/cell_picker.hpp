// The PLC device's view of a cell: its trigger picks through the cell's one
// LOCATE path (cell/cell_locate, as the robot port's LOCATE), its error
// codes are the robot protocol's, its calibration state is the cell's reply
// frame.
#pragma once

#include "picksight/cell/cell_locate.hpp"
#include "picksight/filmstrip/filmstrip.hpp"
#include "picksight/jobs/job_switch.hpp"
#include "picksight/plc/plc_device.hpp"
#include "picksight/results/results_publisher.hpp"

namespace picksight::plc {

uint16_t frameCode(store::CoordinateFrame frame);  // kFrame*

// A LOCATE's poses as the PLC registers hold them: each pose with its
// part's type and score.
PlcResult plcResult(const cell::CellLocate& located);

// The three callbacks of a PlcDevice over `cell` (borrowed; outlives the
// device). The picker publishes each trigger's record on `results` and
// keeps its frame in `filmstrip` when they are set (read at each trigger;
// the pointers outlive the device).
PlcDevice::Picker cellPicker(cell::CellContext& cell, results::ResultsPublisher* const& results,
                             filmstrip::Filmstrip* const& filmstrip);
PlcDevice::FrameState cellFrameState(const store::CellCalibration& calibration);
int robotErrorCodeOf(const Error& error);
// LOAD_JOB over `jobs` (borrowed; outlives the device): the job numbered
// so (jobs::jobNumber), and the number of the job in force.
PlcDevice::JobLoader cellJobLoader(jobs::JobSwitch& jobs);
PlcDevice::JobState cellJobState(const jobs::JobSwitch& jobs);

}  // namespace picksight::plc
