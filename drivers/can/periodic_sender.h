// Frames a drive must keep receiving while the loop does not run, written on a thread of their
// own, each on its own period (not RT: started and stopped by configure, enable and disable).
//
// - ODrive 0.5 checks its axis watchdog on every control-loop pass in every axis state, IDLE
//   included (firmware fw-v0.5.6 MotorControl/main.cpp, Axis::watchdog_check), so an axis
//   nobody talks to between configure and enable, or while a fault is held, latches
//   WATCHDOG_TIMER_EXPIRED; every frame addressed to the axis feeds it
//   (communication/can/can_simple.cpp, do_command). Never while the loop servoes: a hung loop
//   must still let the watchdog stop the motor.
// - A CiA 402 drive that watches SYNC (CANopenNode 301/CO_SYNC.c: an EMCY 0x8100 once 1.5
//   communication cycles pass without one) and hapticd's heartbeat (0x1016) must keep seeing
//   both, one SYNC per cycle, until the stop has switched those watchdogs off.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <thread>
#include <vector>

#include "drivers/can/can_socket.h"
#include "drivers/io/stop_event.h"

namespace hapticd::drivers::can {

class PeriodicSender {
 public:
  struct Entry {
    CanFrame frame;
    std::int64_t period_ns = 0;
    std::int64_t first_ns = 0;  // CLOCK_MONOTONIC of the first write; 0: at once
  };

  PeriodicSender() = default;
  ~PeriodicSender() { stop(); }
  PeriodicSender(const PeriodicSender&) = delete;
  PeriodicSender& operator=(const PeriodicSender&) = delete;

  // Not RT-safe. Writes each entry's frame to `fd` on its period until stop(); the caller keeps
  // fd open until then. `priority` > 0 asks for SCHED_FIFO (refused without privileges: the
  // periods are then kept as well as the host allows). Does nothing when already running.
  void start(int fd, std::vector<Entry> entries, int priority = 0);
  // Not RT-safe, never throws. Joins the thread. Idempotent.
  void stop() noexcept;
  bool running() const noexcept { return thread_.joinable(); }
  // Not RT-safe: blocks until the first entry has been written `n` times (or stop()).
  void wait_written(std::uint64_t n) const noexcept;

 private:
  void run(int fd, std::vector<Entry> entries, int priority) noexcept;

  std::thread thread_;
  std::optional<io::StopEvent> stop_;  // while running
  std::atomic<std::uint64_t> first_written_{0};
};

}  // namespace hapticd::drivers::can
