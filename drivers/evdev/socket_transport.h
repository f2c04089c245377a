// The evdev transport over the loopback socketpair (evdev_wire.h): the simulated device on the
// other end stands in for the kernel's input device. An ioctl is a request answered by the
// device; an EV_FF write is sent without waiting. An effect update waits for the device's
// answer as EVIOCSFF does, on a socketpair of its own (kAnswers, made at construction): the
// update thread reads the answers there while the RT thread reads the events here.
#pragma once

#include <array>
#include <chrono>
#include <vector>

#include "drivers/evdev/evdev_transport.h"
#include "drivers/io/unique_fd.h"

namespace hapticd::drivers::evdev {

class SocketTransport final : public EvdevTransport {
 public:
  // Not RT-safe. Hands the device the descriptor it answers updates on; throws DeviceError
  // when it cannot.
  SocketTransport(io::UniqueFd fd, std::chrono::milliseconds timeout);

  std::string describe() const override { return "the simulated device over a socketpair"; }
  wire::Facts facts(int code) override;
  // The simulated device reports no fuzz, so the driver never sets one there.
  void set_fuzz(int code, int fuzz) override;
  void grab(bool on) override;
  int upload(const wire::Effect& effect) override;
  int erase(int id) noexcept override;
  int update(const wire::Effect& effect) noexcept override;
  int write_ff(int code, int value) noexcept override;
  ReadStatus read(wire::Event& ev, int& error) noexcept override;
  void set_emergency_effects(int first, int second) noexcept override;
  void emergency() noexcept override;

 private:
  // Sends `m` and waits for the answer of type `answer` (events before it are dropped: they
  // precede what the request changes). Throws DeviceError on a time-out or a broken pair.
  wire::Message request(const wire::Message& m, wire::Type answer);
  int send_bytes(const std::uint8_t* data, std::size_t size) noexcept;

  void hand_over_answers();
  int await_answer() noexcept;

  io::UniqueFd fd_;
  io::UniqueFd answers_;  // the update thread's: where the device answers each update
  std::chrono::milliseconds timeout_;
  std::array<std::uint8_t, wire::kMaxMessage> rx_{};
  std::array<std::uint8_t, 32> tx_{};   // the RT thread's EV_FF writes
  std::array<std::uint8_t, 32> utx_{};  // the update thread's
  std::array<std::uint8_t, 32> urx_{};
  // The emergency stops, prebuilt: one per effect.
  std::array<std::array<std::uint8_t, 32>, 2> stop_{};
  std::array<std::size_t, 2> stop_size_{};
};

}  // namespace hapticd::drivers::evdev
