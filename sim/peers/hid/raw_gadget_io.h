// What raw_gadget_peer.cpp and raw_gadget_control.cpp share: the raw gadget's transfer
// block and which of its errors mean the gadget itself is broken. Internal to the peer.
#pragma once

#include <linux/usb/raw_gadget.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstring>

namespace hapticd::sim::hid::raw_gadget_io {

inline constexpr std::size_t kMaxTransfer = 4096;  // a report, a descriptor: far below this

// A raw gadget transfer as the ioctls take it: the kernel's header (which ends in a flexible
// array) followed by the data, in one block. The header is copied in, never aliased.
class Transfer {
 public:
  Transfer(int ep, std::size_t length, bool zero_length_end = false) {
    const usb_raw_ep_io h{static_cast<__u16>(ep),
                          static_cast<__u16>(zero_length_end ? USB_RAW_IO_FLAGS_ZERO : 0),
                          static_cast<__u32>(std::min(length, kMaxTransfer))};
    std::memcpy(bytes_.data(), &h, sizeof h);
  }
  void* arg() noexcept { return bytes_.data(); }
  std::uint8_t* data() noexcept { return bytes_.data() + sizeof(usb_raw_ep_io); }
  std::size_t capacity() const noexcept { return kMaxTransfer; }

 private:
  alignas(usb_raw_ep_io) std::array<std::uint8_t, sizeof(usb_raw_ep_io) + kMaxTransfer> bytes_{};
};

// What the raw gadget answers when it (not one transfer) is broken: its state is not running,
// the request is not pending, or it failed and will refuse everything from now on. Anything
// else is one transfer's outcome (the host gave up, reset the bus, or cancelled).
inline bool gadget_broken(int error) {
  return error == EINVAL || error == EBUSY || error == ENODEV || error == EFAULT;
}

}  // namespace hapticd::sim::hid::raw_gadget_io
