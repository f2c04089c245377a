// The transport seam of the HID driver: what the protocol code (hid_device.cpp) needs from a
// HID device, implemented once over hidapi (hidapi_transport.h, real hardware through hidraw
// or libusb) and once over a SOCK_SEQPACKET socketpair with the loopback peer
// (socket_transport.h, framing in hid_framing.h). Reports travel as hidapi carries them: the
// report id first for numbered reports (and always for output and feature reports, 0 when the
// device does not number them).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace hapticd::drivers::hid {

enum class TransportIo : std::uint8_t {
  kOk,     // read: one report in the buffer; write: handed on
  kEmpty,  // read: nothing pending; write: the output queue is full (nothing sent)
  kError,  // the transport failed (errno in IoResult::error)
};

struct IoResult {
  TransportIo status = TransportIo::kEmpty;
  std::size_t size = 0;  // read: bytes of the report
  int error = 0;         // kError: the errno
};

class HidTransport {
 public:
  virtual ~HidTransport() = default;

  // Not RT-safe. One line naming the device and the way to it, for DeviceInfo::description.
  virtual std::string describe() const = 0;
  // Not RT-safe; each throws DeviceError naming what failed. The report descriptor.
  virtual std::vector<std::uint8_t> report_descriptor() = 0;
  // Sends a feature report (id first).
  virtual void set_feature(std::span<const std::uint8_t> report) = 0;
  // Reads feature report `id` (at most `length` bytes including the id); returns it id first.
  virtual std::vector<std::uint8_t> get_feature(std::uint8_t id, std::size_t length) = 0;
  // Not RT-safe, never throws. Waits until every output report written so far has gone to
  // the device; false when that took longer than `timeout` or the transport failed.
  virtual bool flush(std::chrono::milliseconds timeout) noexcept = 0;

  // RT-safe: called every tick. The next pending input report into `buffer` (truncated to
  // it; a longer report reads as kError with EMSGSIZE), or kEmpty at once.
  virtual IoResult read(std::span<std::uint8_t> buffer) noexcept = 0;
  // RT-safe: called every tick. Hands one output report on without blocking; kEmpty when
  // the device has not taken the previous ones (the report is dropped, the caller counts).
  virtual IoResult write(std::span<const std::uint8_t> report) noexcept = 0;

  // Not RT-safe. The output reports that make the device safe (zero force, output off), in
  // the order they must be sent; write_safe() and emergency() send these.
  virtual void set_safe_reports(std::vector<std::vector<std::uint8_t>> reports) = 0;
  // RT-safe. Sends the safe reports ahead of anything still queued (which is dropped: after
  // a fault nothing but zero may reach the device).
  virtual void write_safe() noexcept = 0;
  // Async-signal-safe: only write(2)/send(2) of the safe reports on an already-open
  // descriptor (a crash handler's last word to the device). Does nothing where the transport
  // has no descriptor that allows it (hidapi's libusb backend).
  virtual void emergency() noexcept = 0;
  // Not RT-safe. What the last failure was, in words ("" if none).
  virtual std::string last_error() const = 0;
};

}  // namespace hapticd::drivers::hid
