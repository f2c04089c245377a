// The HID transport over one end of a SOCK_SEQPACKET socketpair, the loopback peer on the
// other (hid_framing.h documents the messages). Reads and writes are single non-blocking
// system calls; feature and descriptor requests wait for their reply, skipping the input
// reports that arrive meanwhile, up to a time-out.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "drivers/hid/hid_framing.h"
#include "drivers/hid/hid_transport.h"
#include "drivers/io/unique_fd.h"

namespace hapticd::drivers::hid {

class SocketTransport final : public HidTransport {
 public:
  SocketTransport(io::UniqueFd fd, std::chrono::milliseconds timeout)
      : fd_(std::move(fd)), timeout_(timeout) {}

  std::string describe() const override { return "the loopback peer (socketpair)"; }
  std::vector<std::uint8_t> report_descriptor() override;
  void set_feature(std::span<const std::uint8_t> report) override;
  std::vector<std::uint8_t> get_feature(std::uint8_t id, std::size_t length) override;
  bool flush(std::chrono::milliseconds) noexcept override { return fd_.get() >= 0; }
  IoResult read(std::span<std::uint8_t> buffer) noexcept override;
  IoResult write(std::span<const std::uint8_t> report) noexcept override;
  void set_safe_reports(std::vector<std::vector<std::uint8_t>> reports) override;
  void write_safe() noexcept override;
  void emergency() noexcept override;
  std::string last_error() const override { return last_error_; }

 private:
  // Sends `request`, then returns the payload of the first reply of type `expected` (its
  // status byte checked); throws DeviceError naming `what` on a time-out or a failure.
  std::vector<std::uint8_t> transact(const std::vector<std::uint8_t>& request, FrameType expected,
                                     const char* what);

  io::UniqueFd fd_;
  std::chrono::milliseconds timeout_;
  std::array<std::uint8_t, kMaxFrame> rx_{};
  std::array<std::uint8_t, kMaxFrame> tx_{};
  std::vector<std::vector<std::uint8_t>> safe_;  // framed, ready to send
  std::string last_error_;
};

}  // namespace hapticd::drivers::hid
