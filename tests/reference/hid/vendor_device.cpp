#include "vendor_device.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "hid_support.h"

namespace hapticd::reference {
namespace {

double seconds_now() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

}  // namespace

VendorDevice::VendorDevice(const VendorDeviceOptions& o)
    : o_(o), axis_(o.mass, o.damping, o.start_position) {
  kernel_test::UhidConfig c;
  c.report_descriptor = kernel_test::vendor_report_descriptor({1, 8, 2, 8});
  c.vendor_id = 0x1209;
  c.product_id = 0x0002;
  c.name = "reference vendor device";
  c.serial = o.serial;
  // Looking for its hidraw node can meet the last device's node as it vanishes: try again.
  for (int attempt = 0;; ++attempt) {
    try {
      uhid_ = std::make_unique<kernel_test::UhidDevice>(c);
      break;
    } catch (const std::exception&) {
      if (attempt == 4) throw;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }
  sampler_ = std::thread([this] { sample_loop(); });
  listener_ = std::thread([this] { output_loop(); });
}

VendorDevice::~VendorDevice() {
  stop_.store(true);
  sampler_.join();
  listener_.join();
  uhid_.reset();
}

// The firmware's loop: the axis moves under the force it holds; each cycle's sample goes out
// numbered (every cycle, or only when the count changed and at the resend interval).
void VendorDevice::sample_loop() {
  const double period = 1.0 / o_.sample_hz;
  double last = seconds_now(), last_sent = 0.0;
  std::uint8_t counter = 0;
  std::int16_t sent_count = 0;
  bool sent_any = false;
  std::uint64_t cycle = 0;
  timespec next;
  clock_gettime(CLOCK_MONOTONIC, &next);
  while (!stop_.load()) {
    const auto step_ns = static_cast<long>(period * 1e9);
    next.tv_nsec += step_ns;
    while (next.tv_nsec >= 1'000'000'000) {
      next.tv_nsec -= 1'000'000'000;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    const double now = seconds_now();
    axis_.step(std::min(now - last, 0.05), on_.load() ? force_.load() : 0.0);
    last = now;
    const double counts = std::nearbyint(axis_.position() / 1e-5);
    const auto count = static_cast<std::int16_t>(std::clamp(counts, -32767.0, 32767.0));
    if (o_.on_change && sent_any && count == sent_count && (now - last_sent) * 1e3 < o_.resend_ms)
      continue;
    ++cycle;
    if (o_.lose_every > 0 && cycle % static_cast<std::uint64_t>(o_.lose_every) == 0) {
      counter = static_cast<std::uint8_t>(counter + o_.lost);  // samples that never left
    }
    const std::vector<std::uint8_t> report = {1,
                                              static_cast<std::uint8_t>(count & 0xFF),
                                              static_cast<std::uint8_t>((count >> 8) & 0xFF),
                                              counter++,
                                              0,
                                              0,
                                              0,
                                              0,
                                              0};
    uhid_->send_input(report);
    reports_.fetch_add(1);
    sent_count = count;
    sent_any = true;
    last_sent = now;
  }
}

// Output report 2: force (i16, mN), enable (1 on), keep-alive. Anything else is ignored.
void VendorDevice::output_loop() {
  while (!stop_.load()) {
    const auto r = uhid_->read_output(std::chrono::milliseconds(50));
    if (!r || r->size() < 4 || (*r)[0] != 2) continue;
    const auto raw = static_cast<std::int16_t>((*r)[1] | (*r)[2] << 8);
    force_.store(raw * 1e-3);
    on_.store((*r)[3] == 1);
  }
}

}  // namespace hapticd::reference
