// The evdev transport over the loopback socketpair (evdev_wire.h): the simulated device on the
// other end stands in for the kernel's input device. An ioctl is a request answered by the
// device; an EV_FF write and an effect update are sent without waiting, and the update's
// answer is read with the events that follow (a refused update is then a transport fault, as
// a failing EVIOCSFF is).
#pragma once

#include <array>
#include <chrono>
#include <vector>

#include "drivers/evdev/evdev_transport.h"
#include "drivers/io/unique_fd.h"

namespace hapticd::drivers::evdev {

class SocketTransport final : public EvdevTransport {
 public:
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
  void set_emergency_effect(int id) noexcept override;
  void emergency() noexcept override;

 private:
  // Sends `m` and waits for the answer of type `answer` (events before it are dropped: they
  // precede what the request changes; so are the answers of updates still unanswered, which
  // come first). Throws DeviceError on a time-out or a broken pair.
  wire::Message request(const wire::Message& m, wire::Type answer);
  int send_bytes(const std::uint8_t* data, std::size_t size) noexcept;

  io::UniqueFd fd_;
  std::chrono::milliseconds timeout_;
  std::array<std::uint8_t, wire::kMaxMessage> rx_{};
  std::array<std::uint8_t, 32> tx_{};
  std::array<std::uint8_t, 32> stop_{};  // the emergency stop, prebuilt
  std::size_t stop_size_ = 0;
  int unanswered_ = 0;  // updates sent whose kStatus has not been read yet
  int refused_ = 0;     // an update's refusal a request passed over: the next read's error
};

}  // namespace hapticd::drivers::evdev
