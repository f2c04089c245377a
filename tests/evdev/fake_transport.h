// A scripted evdev transport for the driver's unit tests: the test queues the events the
// kernel would hand over and reads what the driver asked of the device (its grabs, uploads,
// updates, EV_FF writes, the fuzz it set), without a kernel or a simulated plant. Updates come
// from the driver's update thread: a test reads `levels` after Device::wait_output() (or a
// disable), and may make each update take `update_delay`, as a slow device in user space does.
#pragma once

#include <atomic>
#include <cerrno>
#include <chrono>
#include <deque>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "drivers/device.h"
#include "drivers/evdev/evdev_transport.h"

namespace hapticd::drivers::evdev::testing {

struct Script {
  wire::Facts facts;
  std::deque<std::pair<ReadStatus, wire::Event>> events;
  int read_error = 0;    // > 0: the next read fails with it (ENODEV: unplugged)
  int update_error = 0;  // > 0: every update fails with it
  std::chrono::milliseconds update_delay{0};  // what each update takes the device
  std::atomic<int> updating{0};               // updates in hand right now
  std::atomic<int> emergencies{0};            // emergency() calls (the crash handler's stop)
  bool grabbed_elsewhere = false;
  bool grabbed = false;
  int fuzz_set = -1;                           // the last fuzz the driver set
  std::vector<int> levels;                     // every update's level
  std::vector<int> directions;                 // every upload's and update's direction
  std::vector<std::pair<int, int>> ff_writes;  // (code, value) written
  std::vector<std::string> calls;              // "update LEVEL", "write CODE VALUE", in order
  int uploads = 0, erases = 0;
  int next_id = 3;
  std::uint64_t library_messages = 0;  // what libevdev would have logged
};

class FakeTransport final : public EvdevTransport {
 public:
  explicit FakeTransport(std::shared_ptr<Script> s) : s_(std::move(s)) {}
  std::string describe() const override { return "fake"; }
  wire::Facts facts(int) override { return s_->facts; }
  void set_fuzz(int, int fuzz) override {
    s_->fuzz_set = fuzz;
    s_->facts.fuzz = fuzz;
  }
  void grab(bool on) override {
    if (on && s_->grabbed_elsewhere) {
      throw DeviceError("evdev: another process has grabbed the device (EVIOCGRAB)");
    }
    s_->grabbed = on;
  }
  int upload(const wire::Effect& e) override {
    ++s_->uploads;
    s_->directions.push_back(e.direction);
    return s_->next_id;
  }
  int erase(int) noexcept override {
    ++s_->erases;
    return 0;
  }
  int update(const wire::Effect& e) noexcept override {
    s_->updating.fetch_add(1);
    if (s_->update_delay.count() > 0) std::this_thread::sleep_for(s_->update_delay);
    s_->levels.push_back(e.level);
    s_->directions.push_back(e.direction);
    s_->calls.push_back("update " + std::to_string(e.level));
    s_->updating.fetch_sub(1);
    return s_->update_error;
  }
  int write_ff(int code, int value) noexcept override {
    s_->ff_writes.emplace_back(code, value);
    s_->calls.push_back("write " + std::to_string(code) + " " + std::to_string(value));
    return 0;
  }
  ReadStatus read(wire::Event& ev, int& error) noexcept override {
    if (s_->read_error != 0) {
      error = s_->read_error;
      return ReadStatus::kError;
    }
    if (s_->events.empty()) return ReadStatus::kEmpty;
    const auto [status, e] = s_->events.front();
    s_->events.pop_front();
    ev = e;
    return status;
  }
  std::uint64_t library_messages() const noexcept override { return s_->library_messages; }
  void set_emergency_effects(int, int) noexcept override {}
  void emergency() noexcept override { s_->emergencies.fetch_add(1); }

 private:
  std::shared_ptr<Script> s_;
};

}  // namespace hapticd::drivers::evdev::testing
