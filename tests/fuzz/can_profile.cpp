// parseCanProfile (staa-can-profile/1): a profile that parses has distinct 11-bit IDs and
// positive finite scales, and its command and odometry frames round-trip through the codec.
// Errors: CanProfileError only.
#include "fuzz_support.hpp"
#include "hal/socketcan/can_codec.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace staa::hal;
  CanProfile p;
  try {
    p = parseCanProfile(staa::fuzz::text(data, size), "fuzz.yaml");
  } catch (const CanProfileError&) {
    return 0;
  }
  const std::uint32_t ids[] = {p.command.id, p.odometry.id, p.status.id, p.heartbeat.host_id, p.heartbeat.base_id};
  for (std::size_t i = 0; i < 5; ++i) {
    staa::fuzz::require(ids[i] <= 0x7FF, "an ID above 0x7FF");
    for (std::size_t j = 0; j < i; ++j) staa::fuzz::require(ids[i] != ids[j], "two frames on one ID");
  }
  for (const double s : {p.command.v_scale, p.command.w_scale, p.odometry.v_scale, p.odometry.w_scale}) {
    staa::fuzz::require(std::isfinite(s) && s > 0.0, "a scale not finite and > 0");
  }
  const auto command = decodeCommand(p, encodeCommand(p, 0.5 * p.command.v_limit, -0.5 * p.command.w_limit, true, false, 7));
  staa::fuzz::require(command.ok(), "an encoded command does not decode", toString(command.error));
  const auto odometry = decodeOdometry(p, encodeOdometry(p, 0.5 * p.odometry.v_limit, 0.0, 10000, 9));
  staa::fuzz::require(odometry.ok() || odometry.error == CanFrameError::kOutOfRange,
                      "an encoded odometry frame does not decode", toString(odometry.error));
  return 0;
}
