#pragma once
// Small text helpers for staad's messages.

#include <string>

namespace staa::staad {

// 's' in single quotes, for a value in a message: "socket '/run/staad.sock': ...".
inline std::string quoted(const std::string& s) {
  std::string q = "'";  // appended: GCC 12 warns falsely (-Wrestrict) on "'" + s + "'"
  q.append(s).append("'");
  return q;
}

}  // namespace staa::staad
