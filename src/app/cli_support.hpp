#pragma once
// Reading numbers from command lines, shared by the tools: std::from_chars (no locale, no
// trailing garbage, a leading '+' allowed as people write it), and the error the tools turn
// into one line on stderr and exit code 2.

#include <charconv>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string_view>

namespace staa::cli {

// Bad command-line input: what() is the whole message after "TOOL: ".
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline std::optional<double> parseDouble(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double v = 0.0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, v);
  if (ec != std::errc{} || ptr != end || text.empty() || !std::isfinite(v)) return std::nullopt;
  return v;
}

inline std::optional<std::uint64_t> parseUnsigned(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  std::uint64_t v = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, v);
  if (ec != std::errc{} || ptr != end || text.empty()) return std::nullopt;
  return v;
}

}  // namespace staa::cli
