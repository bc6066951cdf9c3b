// System errors and error descriptions.
#include "picksight/common/error.hpp"

namespace picksight {

Error systemError(int errno_value, std::string message) {
  return Error{std::error_code(errno_value, std::generic_category()), std::move(message)};
}

std::string describe(const Error& error) {
  return std::string(error.code.category().name()) + "/" + error.code.message() + ": " +
         error.message;
}

}  // namespace picksight
