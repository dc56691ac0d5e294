#include "rt/stall_probe.hpp"

namespace staa::rt {

void StallProbe::begin(Nanos woke) {
  last_read_ = woke;
  gap_ = 0;
  open_ = true;
}

Nanos StallProbe::read(Nanos t) {
  // Outside a cycle (set-up, a test's lockstep run without begin) nothing is measured.
  if (open_ && t - last_read_ > gap_) gap_ = t - last_read_;
  last_read_ = t;
  return t;
}

Nanos StallProbe::end(Nanos now) {
  read(now);
  last_gap_ = gap_;
  open_ = false;
  return last_gap_;
}

StallProbe& StallProbe::local() {
  thread_local StallProbe probe;
  return probe;
}

Nanos StallProbe::now() { return local().read(monotonicNow()); }

}  // namespace staa::rt
