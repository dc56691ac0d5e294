// parseRequest (the control socket's line protocol): a request that parses serializes
// (requestLine) to a line that parses back to an equal request, bit for bit. A bad line is
// an error string, never an exception.
#include "fuzz_support.hpp"
#include "app/staad/protocol.hpp"

#include <cstring>

namespace {
using namespace staa::staad;

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

bool sameRequest(const Request& a, const Request& b) {
  return a.kind == b.kind && sameBits(a.pose.x, b.pose.x) && sameBits(a.pose.y, b.pose.y) &&
         sameBits(a.pose.theta, b.pose.theta) && a.goal_id == b.goal_id && a.debug == b.debug &&
         a.debug_ms == b.debug_ms && a.debug_on == b.debug_on &&
         std::string_view(a.file.data()) == std::string_view(b.file.data());
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto parsed = parseRequest(std::string_view(reinterpret_cast<const char*>(data), size));
  if (const auto* error = std::get_if<std::string>(&parsed)) {
    staa::fuzz::require(!error->empty(), "an empty error message");
    (void)errorReply(*error);  // the reply must serialize whatever the error quotes
    return 0;
  }
  const Request& request = std::get<Request>(parsed);
  std::string line = requestLine(request);
  staa::fuzz::require(!line.empty() && line.back() == '\n', "requestLine does not end in a newline");
  line.pop_back();
  const auto again = parseRequest(line);
  if (const auto* error = std::get_if<std::string>(&again)) staa::fuzz::violated("requestLine does not parse", *error + ": " + line);
  staa::fuzz::require(sameRequest(std::get<Request>(again), request), "requestLine parses to another request", line);
  return 0;
}
