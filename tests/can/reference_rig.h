// The CAN driver against a reference drive (tests/reference/can: written from the firmware and
// the specifications, not from the driver's codecs) over a socketpair, the drive on its own
// thread and clock as on a bus: as a person with that drive would run hapticd, in every test
// run. The kernel tests run the same drives on vcan.
#pragma once

#include <pthread.h>
#include <sched.h>

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "can_rig.h"
#include "reference/can/reference_plant.h"
#include "reference/can/reference_runner.h"

namespace hapticd::drivers::can::testing {

// SCHED_FIFO for the scope (best effort; restored after), as the loop's thread runs.
class RealTime {
 public:
  RealTime() {
    pthread_getschedparam(pthread_self(), &policy_, &param_);
    sched_param p{};
    p.sched_priority = 80;
    pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
  }
  ~RealTime() { pthread_setschedparam(pthread_self(), policy_, &param_); }

 private:
  int policy_ = SCHED_OTHER;
  sched_param param_{};
};

struct ReferenceRig {
  ReferenceRig(const config::Config& c, reference::ReferenceDevice& drive) : cfg(c) {
    auto [mine, theirs] = io::seqpacket_pair();
    auto fd = std::make_shared<io::UniqueFd>(std::move(mine));
    device = make_can_device(cfg, [fd] { return CanSocket::adopt(std::move(*fd), "pair"); });
    runner = std::make_unique<reference::ReferenceRunner>(
        drive, reference::CanPort::adopt(theirs.release()), 70);
  }
  ~ReferenceRig() {
    device->close();
    runner->stop();
  }
  // Ticks for `ms` at the configured period, as the loop would (read, then write `force`);
  // the first fault status, or kOk.
  IoStatus run(double force, int ms) {
    RealTime rt;  // ticks as the loop's thread would: SCHED_FIFO where allowed
    const auto period =
        std::chrono::nanoseconds(static_cast<std::int64_t>(cfg.loop.sample_period_s() * 1e9));
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    auto next = std::chrono::steady_clock::now();
    PositionSample s;
    while (std::chrono::steady_clock::now() < end) {
      IoStatus r = device->read(s);
      if (r == IoStatus::kOk) samples.push_back(s);
      if (r != IoStatus::kTransportFault && r != IoStatus::kDeviceFault) r = device->write(force);
      if (r == IoStatus::kTransportFault || r == IoStatus::kDeviceFault) return r;
      next += period;
      if (next >= end) break;  // the stop that follows comes within the cycle, as the loop's
      std::this_thread::sleep_until(next);
    }
    return IoStatus::kOk;
  }

  config::Config cfg;
  std::unique_ptr<Device> device;
  std::unique_ptr<reference::ReferenceRunner> runner;
  std::vector<PositionSample> samples;
};

// The reference drive's axis in these tests: damping 10 N s/m, so 1 N moves it at 0.1 m/s
// (10 000 counts/s).
inline reference::PlantParameters damped_axis() {
  reference::PlantParameters p;
  p.damping = 10.0;
  return p;
}

inline void sleep_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

// Until `done` holds, or `ms` pass: the reference device answers from its own thread, which a
// loaded host may hold up for longer than any fixed sleep.
inline bool eventually(const std::function<bool()>& done, int ms = 2000) {
  for (int waited = 0; waited < ms; waited += 5) {
    if (done()) return true;
    sleep_ms(5);
  }
  return done();
}

inline std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += l + "\n";
  return out;
}

}  // namespace hapticd::drivers::can::testing
