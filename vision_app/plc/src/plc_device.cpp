// The PLC handshake on a libmodbus register mapping: requests are screened
// here (libmodbus itself would sleep and flush the socket on some bad
// requests), then libmodbus reads or writes the mapping and replies.
#include "picksight/plc/plc_device.hpp"

#include <cstring>
#include <exception>
#include <stdexcept>

#include "picksight/common/log.hpp"

namespace picksight::plc {
namespace {
constexpr size_t kMbapSize = 7;  // transaction, protocol, length, unit
constexpr auto kHeartbeatTick = std::chrono::milliseconds(100);

uint16_t word(const uint8_t* p) { return static_cast<uint16_t>(p[0] << 8 | p[1]); }

bool inMap(uint32_t address, uint32_t count) { return address + count <= reg::kCount; }
bool writable(uint32_t address, uint32_t count) { return address + count <= reg::kWritableEnd; }

// Values the PLC may write: the part type is checked, control bits beyond
// the known ones are ignored.
int checkValues(uint16_t address, const uint8_t* values, uint16_t count) {
  for (uint16_t i = 0; i < count; ++i) {
    const uint16_t v = word(values + 2 * i);
    if (address + i == reg::kPartType && v > kMaxType && v != kAllTypes)
      return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
    if (address + i == reg::kJobNumber && v > kMaxJobNumber)
      return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  }
  return 0;
}
}  // namespace

std::optional<size_t> aduLength(const uint8_t* data, size_t size) {
  if (size < 6) return size_t{0};
  const uint16_t protocol = word(data + 2);
  const uint16_t length = word(data + 4);  // unit + PDU
  // A PDU is at most 253 bytes; one byte of function code at least.
  if (protocol != 0 || length < 2 || length > 254) return std::nullopt;
  const size_t total = 6u + length;
  return size >= total ? total : 0;
}

PlcDevice::PlcDevice(PlcDeviceOptions options, Picker picker, FrameState frame_state,
                     ErrorCode error_code)
    : options_(options),
      picker_(std::move(picker)),
      frame_state_(std::move(frame_state)),
      error_code_(std::move(error_code)) {
  // The same image as holding registers (read/write) and input registers
  // (read only), for PLCs that read results with function 4.
  mapping_ = modbus_mapping_new(0, 0, reg::kCount, reg::kCount);
  if (!mapping_) throw std::runtime_error("PLC registers: out of memory");
  std::lock_guard<std::mutex> lock(mutex_);
  refreshStatus();
}

PlcDevice::~PlcDevice() {
  stop();
  modbus_mapping_free(mapping_);
}

void PlcDevice::setJobs(JobLoader loader, JobState state) {
  std::lock_guard<std::mutex> lock(mutex_);
  job_loader_ = std::move(loader);
  job_state_ = std::move(state);
}

void PlcDevice::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (worker_.joinable()) return;
  stop_ = false;
  worker_ = std::thread([this] { workerLoop(); });
}

void PlcDevice::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

std::vector<uint16_t> PlcDevice::registers() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::vector<uint16_t>(mapping_->tab_registers, mapping_->tab_registers + reg::kCount);
}

int PlcDevice::screen(const uint8_t* pdu, size_t n) const {
  switch (pdu[0]) {
    case MODBUS_FC_READ_HOLDING_REGISTERS:
    case MODBUS_FC_READ_INPUT_REGISTERS: {
      if (n != 5) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
      const uint16_t count = word(pdu + 3);
      if (count < 1 || count > MODBUS_MAX_READ_REGISTERS)
        return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
      return inMap(word(pdu + 1), count) ? 0 : MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS;
    }
    case MODBUS_FC_WRITE_SINGLE_REGISTER:
      if (n != 5) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
      if (!writable(word(pdu + 1), 1)) return MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS;
      return checkValues(word(pdu + 1), pdu + 3, 1);
    case MODBUS_FC_WRITE_MULTIPLE_REGISTERS: {
      if (n < 6 || n != 6u + pdu[5]) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
      const uint16_t count = word(pdu + 3);
      if (count < 1 || count > MODBUS_MAX_WRITE_REGISTERS || pdu[5] != 2 * count)
        return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
      if (!writable(word(pdu + 1), count)) return MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS;
      return checkValues(word(pdu + 1), pdu + 6, count);
    }
    case MODBUS_FC_WRITE_AND_READ_REGISTERS: {
      if (n < 10 || n != 10u + pdu[9]) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
      const uint16_t read_count = word(pdu + 3);
      const uint16_t write_count = word(pdu + 7);
      if (read_count < 1 || read_count > MODBUS_MAX_WR_READ_REGISTERS || write_count < 1 ||
          write_count > MODBUS_MAX_WR_WRITE_REGISTERS || pdu[9] != 2 * write_count)
        return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
      if (!inMap(word(pdu + 1), read_count) || !writable(word(pdu + 5), write_count))
        return MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS;
      return checkValues(word(pdu + 5), pdu + 10, write_count);
    }
    default:
      // Coils and discrete inputs are not served: the bits are in words.
      return MODBUS_EXCEPTION_ILLEGAL_FUNCTION;
  }
}

bool PlcDevice::handle(modbus_t* ctx, const uint8_t* adu, size_t size) {
  const auto length = aduLength(adu, size);
  if (!length || *length != size || size <= kMbapSize) return false;  // the server frames it
  const uint8_t unit = adu[6];
  const uint8_t* pdu = adu + kMbapSize;
  const size_t pdu_size = size - kMbapSize;
  // 128..255 are exception codes, never requests: a peer sending one is not
  // a Modbus client (and libmodbus could not echo the code in an exception).
  if (pdu[0] & 0x80) return false;
  std::lock_guard<std::mutex> lock(mutex_);
  int exception = unit == options_.unit_id || unit == 0 || unit == 0xFF
                      ? screen(pdu, pdu_size)
                      : MODBUS_EXCEPTION_GATEWAY_TARGET;
  if (exception != 0) return modbus_reply_exception(ctx, adu, static_cast<unsigned>(exception)) > 0;

  uint16_t* r = mapping_->tab_registers;
  const auto ticks = (std::chrono::steady_clock::now() - started_) / kHeartbeatTick;
  r[reg::kHeartbeat] = static_cast<uint16_t>(ticks);
  r[reg::kCalibration] = frame_state_();
  if (job_state_) r[reg::kJobInForce] = job_state_();
  refreshStatus();
  if (pdu[0] == MODBUS_FC_READ_INPUT_REGISTERS)
    std::memcpy(mapping_->tab_input_registers, r, sizeof(uint16_t) * reg::kCount);
  const int sent = modbus_reply(ctx, adu, static_cast<int>(size), mapping_);
  // A write counts even when its echo could not be sent: it is in the registers.
  if (pdu[0] != MODBUS_FC_READ_HOLDING_REGISTERS && pdu[0] != MODBUS_FC_READ_INPUT_REGISTERS)
    onControl(r[reg::kControl]);
  return sent > 0;
}

void PlcDevice::onControl(uint16_t written) {
  uint16_t* r = mapping_->tab_registers;
  const uint16_t control = written & kControlMask;
  r[reg::kControl] = control;
  const uint16_t rising = control & ~control_;
  const uint16_t falling = control_ & ~control;
  control_ = control;
  if (falling & kControlTrigger) trigger_ack_ = false;
  if (rising & kControlClearError) {
    error_ = false;
    r[reg::kErrorCode] = 0;
  }
  if ((rising & kControlResultsAck) && results_valid_) results_valid_ = false;
  if (falling & kControlLoadJob) job_done_ = false;
  if (rising & kControlLoadJob) {
    // As a trigger: one request at a time; the results of the job before
    // are no longer valid.
    if (busy_ || stop_ || !worker_.joinable()) {
      ++r[reg::kMissedTriggers];
    } else {
      busy_ = true;
      job_done_ = false;
      error_ = false;
      r[reg::kErrorCode] = 0;
      results_valid_ = false;
      clearResult();
      job_load_ = r[reg::kJobNumber];
      wake_.notify_all();
    }
  }
  if (rising & kControlTrigger) {
    if (busy_ || results_valid_ || stop_ || !worker_.joinable()) {
      ++r[reg::kMissedTriggers];
    } else {
      busy_ = true;
      trigger_ack_ = true;
      error_ = false;
      r[reg::kErrorCode] = 0;
      ++r[reg::kTriggerCount];
      clearResult();
      const uint16_t type = r[reg::kPartType];
      job_ = type == kAllTypes ? -1 : static_cast<int>(type);
      wake_.notify_all();
    }
  }
  refreshStatus();
}

void PlcDevice::refreshStatus() {
  uint16_t* r = mapping_->tab_registers;
  uint16_t status = 0;
  if (!busy_ && !results_valid_ && worker_.joinable() && !stop_) status |= kStatusReady;
  if (busy_) status |= kStatusBusy;
  if (trigger_ack_) status |= kStatusTriggerAck;
  if (results_valid_) status |= kStatusResultsValid;
  if (error_) status |= kStatusError;
  if (r[reg::kCalibration] == kFrameRobot) status |= kStatusCalibrated;
  if (job_done_) status |= kStatusJobDone;
  r[reg::kStatus] = status;
}

void PlcDevice::clearResult() {
  uint16_t* r = mapping_->tab_registers;
  std::fill(r + reg::kFrameSequence, r + reg::kCount, uint16_t{0});
  r[reg::kResultFrame] = 0;
}

void PlcDevice::writeResult(const PlcResult& result) {
  uint16_t* r = mapping_->tab_registers;
  const WordOrder order = options_.word_order;
  clearResult();
  r[reg::kResultFrame] = result.frame;
  putU32(r + reg::kFrameSequence, static_cast<uint32_t>(result.frame_sequence), order);
  const size_t shown = std::min(result.parts.size(), reg::kMaxParts);
  r[reg::kPartCount] = static_cast<uint16_t>(shown);
  r[reg::kPartsOffered] = static_cast<uint16_t>(std::min<size_t>(result.parts.size(), 0xFFFF));
  for (size_t i = 0; i < shown; ++i) {
    const PlcPart& p = result.parts[i];
    uint16_t* block = r + reg::kFirstPart + reg::kPartStride * i;
    block[reg::kOffsetType] = static_cast<uint16_t>(static_cast<int16_t>(p.type));
    putFloat(block + reg::kOffsetX, static_cast<float>(p.x), order);
    putFloat(block + reg::kOffsetY, static_cast<float>(p.y), order);
    putFloat(block + reg::kOffsetRz, static_cast<float>(p.rz), order);
    putFloat(block + reg::kOffsetScore, static_cast<float>(p.score), order);
  }
}

void PlcDevice::workerLoop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || job_.has_value() || job_load_.has_value(); });
    if (stop_) break;
    if (job_load_) {
      loadJob(lock);
      continue;
    }
    const int type = *job_;
    job_.reset();
    lock.unlock();
    // The LOCATE runs without the registers' lock: the PLC keeps polling.
    Result<PlcResult> result = makeError(std::errc::state_not_recoverable, "not run");
    try {
      result = picker_(type);
    } catch (const std::exception& e) {
      logError("PLC trigger: ", e.what());
    }
    const int code = result ? 0 : error_code_(result.error());
    if (!result) logInfo("PLC trigger (type ", type, "): ", result.error().message);
    lock.lock();
    if (result) {
      writeResult(*result);
      results_valid_ = true;
    } else {
      error_ = true;
      mapping_->tab_registers[reg::kErrorCode] = static_cast<uint16_t>(code);
    }
    busy_ = false;
    refreshStatus();
  }
  // A trigger that was accepted but not run leaves the device idle.
  busy_ = false;
  job_.reset();
  job_load_.reset();
  refreshStatus();
}

void PlcDevice::loadJob(std::unique_lock<std::mutex>& lock) {
  const uint16_t number = *job_load_;
  job_load_.reset();
  const JobLoader loader = job_loader_;
  lock.unlock();
  // The load runs without the registers' lock: the PLC keeps polling.
  Result<void> loaded =
      makeError(std::errc::operation_not_supported, "this cell has no jobs to select from the PLC");
  try {
    if (loader) loaded = loader(number);
  } catch (const std::exception& e) {
    logError("PLC job load: ", e.what());
    loaded = makeError(std::errc::state_not_recoverable, e.what());
  }
  const int code = loaded ? 0 : error_code_(loaded.error());
  if (!loaded) logInfo("PLC job load (", number, "): ", loaded.error().message);
  lock.lock();
  if (!loaded) {
    error_ = true;
    mapping_->tab_registers[reg::kErrorCode] = static_cast<uint16_t>(code);
  }
  if (job_state_) mapping_->tab_registers[reg::kJobInForce] = job_state_();
  job_done_ = (control_ & kControlLoadJob) != 0;
  busy_ = false;
  refreshStatus();
}

}  // namespace picksight::plc
