// The PLC port's holding registers (docs/PLC.md has the table and the
// handshake): addresses, bits, and the 32-bit values split over two
// registers in the word order the PLC expects.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace picksight::plc {

// Register addresses (0-based, as on the wire).
namespace reg {
constexpr uint16_t kControl = 0;          // PLC writes: the kControl* bits
constexpr uint16_t kPartType = 1;         // PLC writes: 0..9999, kAllTypes
constexpr uint16_t kJobNumber = 2;        // PLC writes: the job LOAD_JOB loads, 1..9999
constexpr uint16_t kWritableEnd = 3;      // [0, kWritableEnd) accept writes
constexpr uint16_t kStatus = 10;          // the kStatus* bits
constexpr uint16_t kHeartbeat = 11;       // +1 every 100 ms, wraps
constexpr uint16_t kErrorCode = 12;       // robot protocol ERROR code, 0 = none
constexpr uint16_t kCalibration = 13;     // the cell's reply frame now (kFrame*)
constexpr uint16_t kResultFrame = 14;     // the frame the results are in (kFrame*)
constexpr uint16_t kTriggerCount = 15;    // triggers accepted, wraps
constexpr uint16_t kMissedTriggers = 16;  // rising edges while not ready, wraps
constexpr uint16_t kJobInForce = 17;      // the number of the job in force, 0 = none
constexpr uint16_t kFrameSequence = 18;   // 32 bits: 18, 19
constexpr uint16_t kPartCount = 20;       // parts in the result registers
constexpr uint16_t kPartsOffered = 21;    // poses LOCATE offered (may exceed kMaxParts)
constexpr uint16_t kFirstPart = 30;
constexpr uint16_t kPartStride = 10;
// Within a part's block: type (INT, -1 = a region with no model), then
// x, y, rz, score as 32-bit floats.
constexpr uint16_t kOffsetType = 0;
constexpr uint16_t kOffsetX = 2;
constexpr uint16_t kOffsetY = 4;
constexpr uint16_t kOffsetRz = 6;
constexpr uint16_t kOffsetScore = 8;
constexpr size_t kMaxParts = 16;
constexpr uint16_t kCount = kFirstPart + kPartStride * kMaxParts;  // 190 registers
}  // namespace reg

constexpr uint16_t kControlTrigger = 1u << 0;
constexpr uint16_t kControlClearError = 1u << 1;
constexpr uint16_t kControlResultsAck = 1u << 2;
constexpr uint16_t kControlLoadJob = 1u << 3;  // rising edge: JOB LOAD of kJobNumber
constexpr uint16_t kControlMask =
    kControlTrigger | kControlClearError | kControlResultsAck | kControlLoadJob;

constexpr uint16_t kStatusReady = 1u << 0;
constexpr uint16_t kStatusBusy = 1u << 1;
constexpr uint16_t kStatusTriggerAck = 1u << 2;
constexpr uint16_t kStatusResultsValid = 1u << 3;
constexpr uint16_t kStatusError = 1u << 4;
constexpr uint16_t kStatusCalibrated = 1u << 5;  // results in the robot frame
constexpr uint16_t kStatusJobDone =
    1u << 6;  // a LOAD_JOB finished (ok or ERROR), until LOAD_JOB falls

constexpr uint16_t kAllTypes = 0xFFFF;  // INT -1 in the PLC
constexpr uint16_t kMaxType = 9999;
constexpr uint16_t kMaxJobNumber = 9999;

// The codes of kCalibration and kResultFrame.
constexpr uint16_t kFrameVisionPixels = 0;
constexpr uint16_t kFrameVisionMm = 1;
constexpr uint16_t kFrameRobot = 2;
// The calibration file is damaged: every trigger fails with error 45.
constexpr uint16_t kFrameDamaged = 0xffff;

// How a 32-bit value lies in two registers: ABCD sends the high word first
// (Modicon, Siemens, Rockwell's usual setting), CDAB the low word first.
enum class WordOrder { kABCD, kCDAB };
std::optional<WordOrder> parseWordOrder(const std::string& text);  // "ABCD", "CDAB"
const char* wordOrderName(WordOrder order);

void putU32(uint16_t* registers, uint32_t value, WordOrder order);
uint32_t getU32(const uint16_t* registers, WordOrder order);
void putFloat(uint16_t* registers, float value, WordOrder order);
float getFloat(const uint16_t* registers, WordOrder order);

}  // namespace picksight::plc
