// The simulated HID device on its end of the loopback socketpair (`hapticd run --loopback`,
// the conformance suite): the messages of drivers/hid/hid_framing.h in, the firmware's
// answers out.
#pragma once

#include <array>
#include <memory>

#include "drivers/hid/hid_framing.h"
#include "drivers/io/unique_fd.h"
#include "sim/peers/hid/hid_firmware.h"

namespace hapticd::sim::hid {

class SocketHidPeer final : public FirmwarePeer {
 public:
  SocketHidPeer(io::UniqueFd fd, std::unique_ptr<HidFirmware> firmware)
      : FirmwarePeer(std::move(firmware)), fd_(std::move(fd)) {}

  void service() override;
  int fd() const noexcept override { return fd_.get(); }
  // kTransportFault: the device vanishes (its end shut down; the firmware, host gone, zeroes).
  bool inject(PeerFault fault) noexcept override;

 private:
  void handle(const drivers::hid::FrameView& f);
  void send(const std::vector<std::uint8_t>& message);

  io::UniqueFd fd_;
  std::array<std::uint8_t, drivers::hid::kMaxFrame> rx_{};
  std::atomic<bool> vanished_{false};
};

}  // namespace hapticd::sim::hid
