// Pins the robot-protocol number text: strict parsing, '.' as decimal point
// whatever the C or C++ locale, 3-decimal formatting without "-0.000".
#include <clocale>
#include <cstring>
#include <locale>
#include <string>
#include <string_view>
#include <vector>

#include <catch2/catch.hpp>

#include "picksight/common/text.hpp"

namespace {

using picksight::formatFixed;
using picksight::parseDouble;
using picksight::parseInt;
using picksight::splitFields;

constexpr double kNone = -123456.0;  // sentinel that no test input parses to

double parsedOrNone(std::string_view text) { return parseDouble(text).value_or(kNone); }

std::vector<std::string> fieldsOf(std::string_view text, std::string_view separators) {
  std::vector<std::string> out;
  for (auto f : splitFields(text, separators)) out.emplace_back(f);
  return out;
}

// A C++ locale with a decimal comma, available on every machine.
struct CommaDecimal : std::numpunct<char> {
  char do_decimal_point() const override { return ','; }
  char do_thousands_sep() const override { return '.'; }
  std::string do_grouping() const override { return "\3"; }
};

// Restores the global C++ locale even when an assertion aborts the test.
class GlobalLocaleGuard {
 public:
  explicit GlobalLocaleGuard(const std::locale& l) : saved_(std::locale::global(l)) {}
  ~GlobalLocaleGuard() { std::locale::global(saved_); }

 private:
  std::locale saved_;
};

// Restores the C locale likewise.
class CLocaleGuard {
 public:
  CLocaleGuard() : saved_(std::setlocale(LC_ALL, nullptr)) {}
  ~CLocaleGuard() { std::setlocale(LC_ALL, saved_.c_str()); }

 private:
  std::string saved_;
};

void checkNumberText() {
  CHECK(parsedOrNone("1.5") == 1.5);
  CHECK(parsedOrNone("-2.25") == -2.25);
  CHECK(parseDouble("1,5") == std::nullopt);
  CHECK(parseInt("+3").value_or(0) == 3);
  CHECK(formatFixed(1.23456) == "1.235");
  CHECK(formatFixed(-1234.5) == "-1234.500");
  CHECK(formatFixed(-0.0001) == "0.000");
}

}  // namespace

TEST_CASE("parseDouble accepts plain decimals with an optional sign", "[common]") {
  CHECK(parsedOrNone("1.5") == 1.5);
  CHECK(parsedOrNone("-2") == -2.0);
  CHECK(parsedOrNone("+3") == 3.0);
  CHECK(parsedOrNone("0") == 0.0);
  CHECK(parsedOrNone("-0.125") == -0.125);
  CHECK(parsedOrNone("250.75") == 250.75);
  CHECK(parsedOrNone("1e3") == 1000.0);
}

TEST_CASE("parseDouble rejects anything that is not a whole finite number", "[common]") {
  for (const char* bad : {"1,5",      "abc", "",      "1.5x", "nan",  "NaN",  "inf",   "-inf",
                          "infinity", "+",   "-",     ".",    " 1.5", "1.5 ", "1.5\n", "+-3",
                          "++3",      "-+3", "1e999", "0x10", "1..5", "1.5.2"}) {
    INFO("input '" << bad << "'");
    CHECK(parseDouble(bad) == std::nullopt);
  }
}

TEST_CASE("parseInt accepts signed integers and rejects the rest", "[common]") {
  CHECK(parseInt("42").value_or(0) == 42);
  CHECK(parseInt("-2").value_or(0) == -2);
  CHECK(parseInt("+3").value_or(0) == 3);
  CHECK(parseInt("0").value_or(1) == 0);
  CHECK(parseInt("9223372036854775807").value_or(0) == 9223372036854775807LL);
  for (const char* bad : {"1.5", "1,5", "abc", "", "3x", "+", "-", " 3", "3 ", "+-3", "++3", "nan",
                          "inf", "99999999999999999999", "0x10"}) {
    INFO("input '" << bad << "'");
    CHECK(parseInt(bad) == std::nullopt);
  }
}

TEST_CASE("formatFixed rounds to 3 decimals and never prints -0.000", "[common]") {
  CHECK(formatFixed(-0.0001) == "0.000");
  CHECK(formatFixed(-0.0) == "0.000");
  CHECK(formatFixed(0.0) == "0.000");
  CHECK(formatFixed(1.23456) == "1.235");
  CHECK(formatFixed(-1.5) == "-1.500");
  CHECK(formatFixed(-0.0006) == "-0.001");
  CHECK(formatFixed(123456.0) == "123456.000");
  CHECK(formatFixed(2.5, 1) == "2.5");
  CHECK(formatFixed(-0.04, 1) == "0.0");
  CHECK(formatFixed(3.14159, 0) == "3");
}

TEST_CASE("number text ignores the global C++ locale", "[common]") {
  GlobalLocaleGuard guard(std::locale(std::locale::classic(), new CommaDecimal));
  checkNumberText();
}

TEST_CASE("number text ignores the C locale", "[common]") {
  CLocaleGuard guard;
  const char* found = nullptr;
  for (const char* name : {"de_DE.UTF-8", "de_DE.utf8", "de_DE", "fr_FR.UTF-8", "fr_FR.utf8"}) {
    if (std::setlocale(LC_ALL, name) != nullptr) {
      found = name;
      break;
    }
  }
  if (found == nullptr) {
    WARN("no locale with a decimal comma is installed (de_DE, fr_FR): C-locale part skipped");
    return;
  }
  INFO("locale " << found);
  // The locale must really use a comma, or this test would pin nothing.
  REQUIRE(std::strcmp(std::localeconv()->decimal_point, ",") == 0);
  checkNumberText();
}

TEST_CASE("splitFields splits on spaces, commas and tabs and drops empty fields", "[common]") {
  const std::string_view seps = " ,\t";
  CHECK(fieldsOf("LOCATE part_a", seps) == std::vector<std::string>{"LOCATE", "part_a"});
  CHECK(fieldsOf("STORE 1.5,-2.25", seps) == std::vector<std::string>{"STORE", "1.5", "-2.25"});
  CHECK(fieldsOf("  a ,, b\t\tc , ", seps) == std::vector<std::string>{"a", "b", "c"});
  CHECK(fieldsOf("single", seps) == std::vector<std::string>{"single"});
  CHECK(fieldsOf("", seps).empty());
  CHECK(fieldsOf(" ,\t ,", seps).empty());
  CHECK(fieldsOf("a+b+c", "+") == std::vector<std::string>{"a", "b", "c"});
}

TEST_CASE("toUpper upper-cases ASCII command words only", "[common]") {
  CHECK(picksight::toUpper("locate Part_1") == "LOCATE PART_1");
  CHECK(picksight::toUpper("") == "");
}
