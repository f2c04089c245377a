#include "switch_pro_style.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "hid_support.h"

namespace hapticd::reference {
namespace {

constexpr std::uint8_t kReportBytes = 63;  // a 64-byte USB report after its id

double seconds_now() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

// Two 12-bit axes into three bytes, as the notes' decoding reads them back.
void put_stick(std::vector<std::uint8_t>& r, std::size_t at, unsigned x, unsigned y) {
  r[at] = static_cast<std::uint8_t>(x & 0xFF);
  r[at + 1] = static_cast<std::uint8_t>(((x >> 8) & 0x0F) | ((y & 0x0F) << 4));
  r[at + 2] = static_cast<std::uint8_t>((y >> 4) & 0xFF);
}

}  // namespace

SwitchProStyle::SwitchProStyle(const SwitchProStyleOptions& o)
    : o_(o), axis_(o.mass, o.damping, o.start_position) {
  kernel_test::UhidConfig c;
  c.report_descriptor =
      kernel_test::vendor_report_descriptor({kInputId, kReportBytes, kOutputId, 8});
  c.vendor_id = kVendor;
  c.product_id = kProduct;
  c.name = "reference Switch-Pro-style device";
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
  firmware_ = std::thread([this] { firmware_loop(); });
  listener_ = std::thread([this] { output_loop(); });
}

SwitchProStyle::~SwitchProStyle() {
  stop_.store(true);
  firmware_.join();
  listener_.join();
  uhid_.reset();
}

// The axis moves every millisecond under the force it holds; every 1/report_hz the report 0x30
// goes out with the stick's X where the axis is.
void SwitchProStyle::firmware_loop() {
  double last = seconds_now(), next_report = last;
  std::uint8_t timer = 0;
  std::uint64_t n = 0;
  timespec next;
  clock_gettime(CLOCK_MONOTONIC, &next);
  while (!stop_.load()) {
    next.tv_nsec += 1'000'000;
    if (next.tv_nsec >= 1'000'000'000) {
      next.tv_nsec -= 1'000'000'000;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    const double now = seconds_now();
    axis_.step(std::min(now - last, 0.05), on_.load() ? force_.load() : 0.0);
    last = now;
    if (now < next_report) continue;
    next_report = std::max(next_report + 1.0 / o_.report_hz, now);
    const double counts = 2048.0 + std::nearbyint(axis_.position() / o_.metres_per_count);
    const auto x = static_cast<unsigned>(std::clamp(counts, 0.0, 4095.0));
    const unsigned y = o_.y_rest + static_cast<unsigned>(n % 3) - 1;  // never quite still
    std::vector<std::uint8_t> r(1 + kReportBytes, 0);
    r[0] = kInputId;
    r[1] = timer;
    timer = static_cast<std::uint8_t>(timer + 1);
    r[2] = 0x81;  // battery 8 (full); connection: Pro Controller, USB powered
    put_stick(r, 1 + 5, x, y);
    put_stick(r, 1 + 8, 2048, 2048);  // the right stick, centred
    r[1 + 11] = 0x70;                 // the vibrator input report, one of the notes' samples
    uhid_->send_input(r);
    reports_.fetch_add(1);
    ++n;
  }
}

// Output report 2: force (i16, mN), enable (1 on), keep-alive. Anything else is ignored.
void SwitchProStyle::output_loop() {
  while (!stop_.load()) {
    const auto r = uhid_->read_output(std::chrono::milliseconds(50));
    if (!r || r->size() < 4 || (*r)[0] != kOutputId) continue;
    const auto raw = static_cast<std::int16_t>((*r)[1] | (*r)[2] << 8);
    force_.store(raw * 1e-3);
    on_.store((*r)[3] == 1);
  }
}

}  // namespace hapticd::reference
