// The transport seam of the evdev driver: what the protocol code (evdev_device.cpp) needs of
// an input device with force feedback, implemented once over the kernel's /dev/input/eventN
// through libevdev (libevdev_transport.h) and once over a SOCK_SEQPACKET socketpair with the
// simulated device (socket_transport.h, framing in evdev_wire.h).
#pragma once

#include <cstdint>
#include <string>

#include "drivers/evdev/evdev_wire.h"

namespace hapticd::drivers::evdev {

enum class ReadStatus : std::uint8_t {
  kEvent,      // one event in `ev`
  kEmpty,      // nothing pending
  kDropped,    // events were lost (SYN_DROPPED): the events that follow are what differs
               // between the events handed over so far and the kernel's state now (nothing, or
               // ending with a SYN_REPORT)
  kError,      // the device failed (errno in `error`; ENODEV when it is gone)
  kMalformed,  // the loopback only: a message that is no event, skipped (the driver counts it)
};

class EvdevTransport {
 public:
  virtual ~EvdevTransport() = default;

  // Not RT-safe. One line naming the device and the way to it.
  virtual std::string describe() const = 0;
  // Not RT-safe; each throws DeviceError naming what failed. The device's facts, with the
  // range and current value of axis `code`.
  virtual wire::Facts facts(int code) = 0;
  // EVIOCSABS: the kernel's fuzz on axis `code` (the rest of its absinfo kept).
  virtual void set_fuzz(int code, int fuzz) = 0;
  // EVIOCGRAB: `on` takes the device for this process alone (EBUSY when another holds it:
  // said so), off gives it back.
  virtual void grab(bool on) = 0;
  // EVIOCSFF of a new effect (id -1): its id.
  virtual int upload(const wire::Effect& effect) = 0;
  // Not RT-safe, never throws. EVIOCRMFF: 0 or an errno.
  virtual int erase(int id) noexcept = 0;

  // Called on the update thread alone (update_thread.h), never allocating: EVIOCSFF of the
  // uploaded effect with a new level, which returns once the device has taken it (a device in
  // user space answers it itself, as slowly as it does): 0 or the errno. The RT thread's
  // read() and write_ff() run meanwhile and must not wait for it.
  virtual int update(const wire::Effect& effect) noexcept = 0;
  // RT-safe. An EV_FF event written to the device (play/stop effect `code`, FF_GAIN,
  // FF_AUTOCENTER): 0 or the errno.
  virtual int write_ff(int code, int value) noexcept = 0;
  // RT-safe: called every tick. The next event, without blocking.
  virtual ReadStatus read(wire::Event& ev, int& error) noexcept = 0;

  // RT-safe. Messages the library behind the transport reported (libevdev's log), counted
  // because nothing on the RT thread may print them.
  virtual std::uint64_t library_messages() const noexcept { return 0; }

  // Not RT-safe. The effects emergency() stops (-1: none): one, or one per axis.
  virtual void set_emergency_effects(int first, int second) noexcept = 0;
  // Async-signal-safe: only write(2) of the stop of those effects on the open descriptor.
  virtual void emergency() noexcept = 0;
};

}  // namespace hapticd::drivers::evdev
