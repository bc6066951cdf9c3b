// The error model: every library names its failures in an enum of its own (a
// domain, as Aravis has error domains), and an Error carries that value typed,
// as a std::error_code, with a message for people. Callers test errors by
// value (`error.code == SourceErrc::kTimeout`), never by number or by the
// text; the robot protocol and the control socket each translate errors to
// their wire codes in one table (vision_app/protocol/src/robot_errors.cpp,
// video_server/src/control_errors.cpp). See docs/ARCHITECTURE.md.
//
// Declaring a domain:
//   namespace picksight::foo {
//   enum class FooErrc { kBar = 1, kBaz };   // 0 is reserved for "no error"
//   const char* errorName(FooErrc e);         // "bar": short, for logs
//   PICKSIGHT_ERROR_DOMAIN(FooErrc, "foo")
//   }
//   PICKSIGHT_ERROR_ENUM(picksight::foo::FooErrc)
#pragma once

#include <string>
#include <system_error>
#include <type_traits>
#include <utility>

namespace picksight {

// The category of one error enum: name() is its domain, message() the
// value's name from errorName().
template <typename E>
class DomainCategory : public std::error_category {
 public:
  explicit DomainCategory(const char* domain) : domain_(domain) {}
  const char* name() const noexcept override { return domain_; }
  std::string message(int value) const override { return errorName(static_cast<E>(value)); }

 private:
  const char* domain_;
};

struct Error {
  std::error_code code;
  std::string message;
};

// An Error of a domain enum (any enum with a make_error_code(), so that it
// works before the enum's PICKSIGHT_ERROR_ENUM, e.g. in its own header).
template <typename E, typename = decltype(make_error_code(std::declval<E>()))>
Error makeError(E code, std::string message) {
  return Error{make_error_code(code), std::move(message)};
}

// An Error from an errno value (files, sockets): the generic category, so it
// compares equal to std::errc values.
Error systemError(int errno_value, std::string message);

// "domain/name: message", for logs.
std::string describe(const Error& error);

}  // namespace picksight

// Inside the enum's namespace: make_error_code() found by argument-dependent
// lookup, with one category object per enum.
#define PICKSIGHT_ERROR_DOMAIN(Enum, domain)                            \
  inline const std::error_category& errorCategory(Enum) {               \
    static const ::picksight::DomainCategory<Enum> category(domain);    \
    return category;                                                    \
  }                                                                     \
  inline std::error_code make_error_code(Enum e) {                      \
    return std::error_code(static_cast<int>(e), errorCategory(Enum{})); \
  }

// At global scope: lets the enum convert to std::error_code.
#define PICKSIGHT_ERROR_ENUM(QualifiedEnum) \
  template <>                               \
  struct std::is_error_code_enum<QualifiedEnum> : std::true_type {};
