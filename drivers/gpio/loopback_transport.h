// The GPIO driver against its simulated peer (sim/peers/gpio/) over one end of an
// io::seqpacket_pair(), speaking gpio_wire.h: edges in, the PWM and direction state out once a
// tick for each joint (the last joint's is the period that clocks the peer's plant).
#pragma once

#include <array>
#include <atomic>

#include "drivers/gpio/gpio_transport.h"
#include "drivers/io/unique_fd.h"

namespace hapticd::drivers::gpio {

class LoopbackTransport final : public GpioTransport {
 public:
  // How long open() waits for the peer's answer to hello.
  static constexpr int kHelloTimeoutMs = 2000;

  LoopbackTransport(io::UniqueFd fd, std::size_t joints) : fd_(std::move(fd)), joints_(joints) {}

  JointLevels open(std::span<const OutputState> off) override;
  void close() noexcept override { open_ = false; }
  JointLevels read_levels() override;
  std::string describe() const override { return "gpio loopback peer (socketpair)"; }
  EdgeRead read_edges(std::span<Edge> buffer) noexcept override;
  int write_output(const OutputState& out) noexcept override;
  void emergency_stop() noexcept override;

  // Any thread: messages that did not decode (counted, dropped, never logged on the RT path).
  std::uint64_t malformed() const noexcept { return malformed_.load(std::memory_order_relaxed); }

 private:
  JointLevels exchange_levels();

  io::UniqueFd fd_;
  std::size_t joints_;
  bool open_ = false;
  std::array<SequenceCheck, base::kMaxJoints> seq_;  // the peer numbers each joint's edges
  std::array<std::uint8_t, wire::kMaxMessageSize> rx_{};
  // Prebuilt for emergency_stop: each joint's zero duty.
  std::array<std::array<std::uint8_t, wire::kOutputSize>, base::kMaxJoints> stop_msg_{};
  std::atomic<std::uint64_t> malformed_{0};
};

}  // namespace hapticd::drivers::gpio
