#include "drivers/hid/hid_settings.h"

#include <cmath>

namespace hapticd::drivers::hid {

const char* to_string(Backend b) noexcept { return b == Backend::kHidraw ? "hidraw" : "libusb"; }
const char* to_string(Profile p) noexcept { return p == Profile::kReport ? "report" : "pid"; }

int declared_delay_samples(double poll_interval_ms, double sample_period_s) noexcept {
  // The round trip in periods, rounded up; a hair of tolerance so 2 ms / 1 ms is 2, not 3.
  const double periods = 2.0 * poll_interval_ms * 1e-3 / sample_period_s;
  const int round_trip = static_cast<int>(std::ceil(periods - 1e-9));
  return std::max(0, round_trip - 1);
}

}  // namespace hapticd::drivers::hid
