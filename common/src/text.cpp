// Locale-independent number text, built on std::from_chars / to_chars.
#include "picksight/common/text.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace picksight {
namespace {
// from_chars takes no '+': drop one. False for "+-3", which from_chars would
// otherwise read as -3.
bool dropPlusSign(std::string_view& text) {
  if (text.empty() || text.front() != '+') return true;
  text.remove_prefix(1);
  return text.empty() || text.front() != '-';
}
}  // namespace

std::optional<double> parseDouble(std::string_view text) {
  if (text.empty()) return std::nullopt;
  if (!dropPlusSign(text)) return std::nullopt;
  double value = 0;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

std::optional<long long> parseInt(std::string_view text) {
  if (text.empty()) return std::nullopt;
  if (!dropPlusSign(text)) return std::nullopt;
  long long value = 0;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || ptr != text.data() + text.size()) return std::nullopt;
  return value;
}

std::string formatFixed(double value, int decimals) {
  if (!std::isfinite(value)) return "nan";
  char buf[64];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value, std::chars_format::fixed, decimals);
  if (ec != std::errc()) return "nan";
  std::string out(buf, ptr);
  // "-0.000" reads as a sign error to a robot programmer.
  if (out[0] == '-' && out.find_first_not_of("-0.") == std::string::npos) out.erase(0, 1);
  return out;
}

std::vector<std::string_view> splitFields(std::string_view text, std::string_view separators) {
  std::vector<std::string_view> fields;
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t start = text.find_first_not_of(separators, pos);
    if (start == std::string_view::npos) break;
    size_t end = text.find_first_of(separators, start);
    if (end == std::string_view::npos) end = text.size();
    fields.push_back(text.substr(start, end - start));
    pos = end;
  }
  return fields;
}

std::string toUpper(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

}  // namespace picksight
