#pragma once

// What the VM probes (tests/vm) share: their main, and the clock they stamp events with.

#include <time.h>

#include <cstdio>
#include <exception>

namespace flowsteer::vm_test {

// CLOCK_REALTIME in seconds: candump stamps frames with it, so the probes' events and the bus
// can be put on one time line.
inline double realtime_s() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// stdout line-buffered, as the console interleaves it with the kernel's messages, and an
// escaping exception printed as "PROBE failed WHAT" with status 1.
template <typename Run>
int probe_main(Run run) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  try {
    return run();
  } catch (const std::exception& e) {
    std::printf("PROBE failed %s\n", e.what());
    return 1;
  }
}

}  // namespace flowsteer::vm_test
