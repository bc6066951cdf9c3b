// Word order of 32-bit values in the PLC registers.
#include "picksight/plc/register_map.hpp"

#include <cstring>

namespace picksight::plc {

std::optional<WordOrder> parseWordOrder(const std::string& text) {
  if (text == "ABCD" || text == "abcd") return WordOrder::kABCD;
  if (text == "CDAB" || text == "cdab") return WordOrder::kCDAB;
  return std::nullopt;
}

const char* wordOrderName(WordOrder order) { return order == WordOrder::kABCD ? "ABCD" : "CDAB"; }

void putU32(uint16_t* registers, uint32_t value, WordOrder order) {
  const auto high = static_cast<uint16_t>(value >> 16);
  const auto low = static_cast<uint16_t>(value & 0xFFFF);
  registers[0] = order == WordOrder::kABCD ? high : low;
  registers[1] = order == WordOrder::kABCD ? low : high;
}

uint32_t getU32(const uint16_t* registers, WordOrder order) {
  const uint32_t first = registers[0];
  const uint32_t second = registers[1];
  return order == WordOrder::kABCD ? (first << 16) | second : (second << 16) | first;
}

void putFloat(uint16_t* registers, float value, WordOrder order) {
  uint32_t bits = 0;
  std::memcpy(&bits, &value, sizeof(bits));  // IEEE-754 binary32 on every target we build for
  putU32(registers, bits, order);
}

float getFloat(const uint16_t* registers, WordOrder order) {
  const uint32_t bits = getU32(registers, order);
  float value = 0;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

}  // namespace picksight::plc
