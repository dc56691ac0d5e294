#pragma once
// The text of an OS error code (errno, or a pthread_* return value), for messages at the
// edges: "Connection refused", or with its symbolic name for searching,
// "Operation not permitted (EPERM)".

#include <string>

namespace staa::rt {

// The system's text for `error` (strerror's), e.g. "Connection refused".
std::string errnoText(int error);

// The text and the symbolic name, e.g. "Operation not permitted (EPERM)".
std::string describeErrno(int error);

}  // namespace staa::rt
