#include "rt/errors.hpp"

#include <cstring>
#include <system_error>

namespace staa::rt {

std::string errnoText(int error) { return std::system_category().message(error); }

std::string describeErrno(int error) {
  std::string out = std::error_code(error, std::generic_category()).message();
  if (const char* name = ::strerrorname_np(error)) {
    out += " (";
    out += name;
    out += ')';
  }
  return out;
}

}  // namespace staa::rt
