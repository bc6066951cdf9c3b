// Locale-independent number parsing and formatting: robot controllers and
// config files always use '.' as the decimal point, whatever the host locale.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace picksight {

std::optional<double> parseDouble(std::string_view text);
std::optional<long long> parseInt(std::string_view text);
// Fixed-point with `decimals` digits, '.' as decimal point, no "-0.000".
std::string formatFixed(double value, int decimals = 3);
// Splits on any of the separator characters, dropping empty fields.
std::vector<std::string_view> splitFields(std::string_view text, std::string_view separators);
std::string toUpper(std::string_view text);

}  // namespace picksight
