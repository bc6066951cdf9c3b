// The vision app as a Modbus device: the register image a PLC reads and
// writes, the trigger / acknowledge / results-valid handshake on it, and
// one worker that runs the LOCATE a trigger asks for. Sockets are the
// server's (modbus_server.hpp): this class answers one framed request at a
// time, so the fuzzer drives it without a network.
//
// Threading: handle() may be called from any thread (the server calls it
// from its one socket thread); it never waits for a LOCATE, which runs on
// the device's own worker thread. Registers are guarded by mutex_.
#pragma once

#include <modbus/modbus.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "picksight/common/result.hpp"
#include "picksight/plc/register_map.hpp"

namespace picksight::plc {

struct PlcPart {
  int type = -1;  // -1: a region, no model
  double x = 0;   // the reply frame's units (pixels, mm), degrees
  double y = 0;
  double rz = 0;
  double score = 0;
};

// A LOCATE as the PLC sees it.
struct PlcResult {
  uint64_t frame_sequence = 0;
  uint16_t frame = kFrameVisionPixels;  // kFrame*
  std::vector<PlcPart> parts;           // every pose offered, best first
};

struct PlcDeviceOptions {
  uint8_t unit_id = 1;  // 0 and 255 ("this device") are answered too
  WordOrder word_order = WordOrder::kABCD;
};

// The length of the first Modbus TCP ADU in `data` once all of it is there,
// 0 while more bytes are needed, nullopt when the header cannot be a Modbus
// request (protocol id not 0, length out of [2, 254]): the stream cannot be
// resynchronized, close the connection.
std::optional<size_t> aduLength(const uint8_t* data, size_t size);

class PlcDevice {
 public:
  // Picks the parts of `type` (-1: every type) in a fresh frame, as the
  // cell's LOCATE does (cell_picker); called on the worker thread.
  using Picker = std::function<Result<PlcResult>(int type)>;
  // The cell's reply frame now (kFrame*); called on handle()'s thread.
  using FrameState = std::function<uint16_t()>;
  // Turns a LOCATE's error into the robot protocol's ERROR code.
  using ErrorCode = std::function<int(const Error&)>;
  // Loads the job of a number (jobs/job_switch.hpp: the job whose name
  // starts with it); called on the worker thread.
  using JobLoader = std::function<Result<void>(uint16_t number)>;
  // The number of the job in force (0: none); called on handle()'s thread.
  using JobState = std::function<uint16_t()>;

  PlcDevice(PlcDeviceOptions options, Picker picker, FrameState frame_state, ErrorCode error_code);
  ~PlcDevice();
  PlcDevice(const PlcDevice&) = delete;
  PlcDevice& operator=(const PlcDevice&) = delete;

  // Lets the PLC select jobs (LOAD_JOB); without it a LOAD_JOB fails
  // (ERROR 99). Call before start().
  void setJobs(JobLoader loader, JobState state);

  // Starts and stops the worker; a LOCATE under way is finished first.
  void start();
  void stop();

  // Answers one complete ADU (aduLength() of it == size) on `ctx`'s socket:
  // the reply, or a Modbus exception for an unknown function, address
  // range, read-only register, bad value or another unit. Returns false
  // when the connection must close: the reply could not be sent, or the
  // function code is an exception code (128..255), which no client sends.
  bool handle(modbus_t* ctx, const uint8_t* adu, size_t size);

  // A copy of the registers, for tests and benchmarks.
  std::vector<uint16_t> registers() const;
  const PlcDeviceOptions& options() const { return options_; }

 private:
  // With mutex_ held.
  void onControl(uint16_t control);
  void refreshStatus();
  void writeResult(const PlcResult& result);
  void clearResult();
  // The Modbus exception code for a request that must not reach the
  // register image, or 0.
  int screen(const uint8_t* pdu, size_t size) const;
  void workerLoop();
  // On the worker, with `lock` (of mutex_) held: runs the job load asked
  // for, without the lock meanwhile.
  void loadJob(std::unique_lock<std::mutex>& lock);

  const PlcDeviceOptions options_;
  const Picker picker_;
  const FrameState frame_state_;
  const ErrorCode error_code_;
  const std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();

  mutable std::mutex mutex_;  // guards everything below
  std::condition_variable wake_;
  modbus_mapping_t* mapping_ = nullptr;
  uint16_t control_ = 0;  // the control bits as last written
  bool busy_ = false;
  bool trigger_ack_ = false;
  bool results_valid_ = false;
  bool error_ = false;
  std::optional<int> job_;            // the type of the LOCATE the worker is to run
  std::optional<uint16_t> job_load_;  // the job number the worker is to load
  bool job_done_ = false;
  JobLoader job_loader_;  // set before start()
  JobState job_state_;
  bool stop_ = false;
  std::thread worker_;
};

}  // namespace picksight::plc
