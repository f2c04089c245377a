// SocketCAN fixtures: a virtual CAN bus (vcan) and CAN_RAW sockets on it. A driver's SocketCAN
// transport binds to the VcanInterface's name; its peer (or the test) is a CanRawSocket on the
// same interface, which sees every frame the driver sends and vice versa.
#pragma once

#include <linux/can.h>
#include <linux/can/raw.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "unique_fd.h"

namespace hapticd::kernel_test {

// A vcan interface created (administratively up) for the fixture's lifetime and deleted
// afterwards. CAN FD capable (MTU CANFD_MTU) unless fd_capable is false.
class VcanInterface {
 public:
  explicit VcanInterface(std::string name = "vcan0", bool fd_capable = true);
  ~VcanInterface();
  VcanInterface(const VcanInterface&) = delete;
  VcanInterface& operator=(const VcanInterface&) = delete;

  const std::string& name() const noexcept { return name_; }
  int index() const noexcept { return index_; }

 private:
  std::string name_;
  int index_ = 0;
};

struct CanRawOptions {
  bool fd_frames = false;           // CAN_RAW_FD_FRAMES: also send and receive CAN FD frames
  std::vector<can_filter> filters;  // CAN_RAW_FILTER; empty keeps the kernel's accept-all
  can_err_mask_t error_mask = 0;    // CAN_RAW_ERR_FILTER: which error frames to receive
};

struct ReceivedCanFrame {
  canfd_frame frame{};  // a classic frame arrives in the first sizeof(can_frame) bytes
  bool is_fd = false;   // the read returned CANFD_MTU bytes
};

// A non-blocking CAN_RAW socket bound to one interface.
class CanRawSocket {
 public:
  CanRawSocket(const VcanInterface& iface, const CanRawOptions& options);

  void send(const can_frame& frame);
  void send(const canfd_frame& frame);
  // The next frame, or nothing when none arrives within TIMEOUT.
  std::optional<ReceivedCanFrame> receive(std::chrono::milliseconds timeout);
  // Reads back CAN_RAW_ERR_FILTER as the kernel holds it.
  can_err_mask_t error_mask() const;
  int fd() const noexcept { return fd_.get(); }

 private:
  UniqueFd fd_;
};

}  // namespace hapticd::kernel_test
