// Every frame decoder of the CAN codec (the driver's and basesim's: both use can_codec) on
// any frame: a frame that decodes re-encodes to the same bytes (the codec is a bijection on
// valid frames); error frames classify without reading past the frame; the rolling counter
// tracker takes any sequence. The first input byte picks the byte order.
#include "fuzz_support.hpp"
#include "hal/socketcan/can_codec.hpp"

#include <cstring>

namespace {
using namespace staa::hal;

void requireSame(const can_frame& decoded_from, const can_frame& reencoded, const char* what) {
  staa::fuzz::require(reencoded.can_id == decoded_from.can_id && reencoded.len == decoded_from.len &&
                          std::memcmp(reencoded.data, decoded_from.data, 8) == 0,
                      what);
}

const CanProfile& profile(bool big_endian) {
  static const CanProfile little{};
  static const CanProfile big = [] {
    CanProfile p;
    p.byte_order = CanByteOrder::kBig;
    return p;
  }();
  return big_endian ? big : little;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  staa::fuzz::Fields in(data, size);
  const CanProfile& p = profile((in.take<std::uint8_t>() & 1) != 0);
  CounterTracker tracker;
  while (in.restSize() > 0) {
    can_frame f{};
    f.can_id = in.take<canid_t>();
    f.len = in.take<std::uint8_t>();
    for (std::uint8_t& b : f.data) b = in.take<std::uint8_t>();

    if (const auto d = decodeCommand(p, f); d.ok()) {
      const CanCommand& c = d.value;
      requireSame(f, encodeCommand(p, c.v, c.w, c.enable, c.brake, c.counter), "command does not re-encode");
    }
    if (const auto d = decodeHostHeartbeat(p, f); d.ok()) {
      requireSame(f, encodeHostHeartbeat(p, d.value.state, d.value.counter), "host heartbeat does not re-encode");
    }
    if (const auto d = decodeOdometry(p, f); d.ok()) {
      const CanOdometry& o = d.value;
      requireSame(f, encodeOdometry(p, o.v, o.w, o.dt_us, o.counter), "odometry does not re-encode");
    }
    if (const auto d = decodeStatus(p, f); d.ok()) {
      const CanStatus& s = d.value;
      requireSame(f, encodeStatus(p, s.enabled, s.estop, s.drive_fault, s.fault_code, s.counter),
                  "status does not re-encode");
    }
    if (const auto d = decodeBaseHeartbeat(p, f); d.ok()) {
      requireSame(f, encodeBaseHeartbeat(p, d.value.state, d.value.counter), "base heartbeat does not re-encode");
    }
    if (isErrorFrame(f)) (void)classifyErrorFrame(f);
    (void)toString(CanFrameError{static_cast<std::uint8_t>(f.data[0] % kCanFrameErrorCount)});
    const CanCounterVerdict verdict = tracker.check(f.data[6]);
    staa::fuzz::require(verdict != CanCounterVerdict::kStale || tracker.started(), "stale before the first frame");
  }
  return 0;
}
