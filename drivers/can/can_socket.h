// The one class that knows SocketCAN (docs/drivers/can.md): a non-blocking CAN_RAW socket on an
// interface, with receive filters for the node's ids, error frames enabled and decoded into
// BusEvents, and SO_TIMESTAMPNS kernel receive times converted to CLOCK_MONOTONIC. The same
// class adopts one end of io::seqpacket_pair(), where each message is one struct can_frame
// (error frames included), so the drivers' protocol code and the simulated drives run
// unchanged over a socketpair or a real bus. Everything above it sees CanFrame only.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "drivers/can/can_frame.h"
#include "drivers/io/unique_fd.h"

namespace hapticd::drivers::can {

// A receive filter: a frame passes when (id & mask) == (filter id & mask) (11-bit ids only).
struct IdFilter {
  std::uint32_t id;
  std::uint32_t mask = kSffMask;
};

// A frame in SocketCAN's own layout (struct can_frame), built before it is needed so that an
// emergency stop only has to write(2) it.
struct WireFrame {
  alignas(8) unsigned char bytes[16];
};

class CanSocket {
 public:
  enum class Io : std::uint8_t {
    kDone,       // a frame (or bus event) was sent or received
    kEmpty,      // receive: nothing waiting; send: the TX queue is full (ENOBUFS, EAGAIN)
    kMalformed,  // receive: a message that is not one struct can_frame (counted, skipped)
    kFailed,     // the socket failed (errno in `error`) or the other end closed (error 0)
  };
  struct Received {
    bool is_event = false;  // an error frame: `event` says what the controller saw
    CanFrame frame;
    BusEvent event;
    std::int64_t time_ns = 0;  // CLOCK_MONOTONIC of the kernel's receive timestamp
  };

  // Not RT-safe. CAN_RAW on `interface`, bound, filtered to `filters` (none: nothing but
  // error frames), error frames of every class when `error_frames`. Throws DeviceError naming
  // the interface and what the kernel said.
  static CanSocket open_interface(const std::string& interface, std::span<const IdFilter> filters,
                                  bool error_frames);
  // Not RT-safe. One end of io::seqpacket_pair(), with receive timestamps.
  static CanSocket adopt(io::UniqueFd fd, std::string description);

  CanSocket(CanSocket&&) noexcept = default;
  CanSocket& operator=(CanSocket&&) noexcept = default;

  // RT-safe: called every tick. One frame, never blocking.
  Io send(const CanFrame& frame, int& error) noexcept;
  // RT-safe: called every tick. The next frame or bus event, never blocking.
  Io receive(Received& out, int& error) noexcept;
  // Not RT-safe. Sends an error frame saying `event` (a simulated controller's report: the
  // peers' bus failure). On a real interface the kernel may refuse it.
  Io send_event(const BusEvent& event, int& error) noexcept;
  // Not RT-safe. Waits until something can be received, at most timeout_ms; false on time-out.
  bool wait_readable(int timeout_ms) const;

  // The frame as write(2) must see it.
  static WireFrame to_wire(const CanFrame& frame) noexcept;
  // Async-signal-safe: write(2) of prebuilt frames, errors ignored (nothing can be done).
  static void write_wire(int fd, std::span<const WireFrame> frames) noexcept;

  int fd() const noexcept { return fd_.get(); }
  const std::string& description() const noexcept { return description_; }
  void close() noexcept { fd_.reset(); }

 private:
  CanSocket(io::UniqueFd fd, std::string description)
      : fd_(std::move(fd)), description_(std::move(description)) {}

  io::UniqueFd fd_;
  std::string description_;
};

}  // namespace hapticd::drivers::can
