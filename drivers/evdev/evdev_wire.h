// The evdev driver's loopback framing: what crosses the SOCK_SEQPACKET socketpair between the
// driver (socket_transport.h) and its simulated device (sim/peers/evdev/) in place of an
// /dev/input/eventN node. Each message stands for one thing the kernel interface does: an
// input event read from the node, an ioctl (the device's facts, EVIOCGRAB, EVIOCSFF,
// EVIOCRMFF) with its answer, or an EV_FF event written to it (play, stop, gain, autocenter).
// An update's answer comes back on a descriptor of its own (kAnswers), as EVIOCSFF's return is
// not in the node's event stream.
// Little-endian, one message per datagram, the type in the first byte. Pure: no OS header, so
// the simulated device speaks the driver's bytes through the same code.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/evdev/evdev_settings.h"

namespace hapticd::drivers::evdev::wire {

enum class Type : std::uint8_t {
  kEvent = 1,  // device -> driver: one input event (type, code, value, time)
  kQuery,      // driver -> device: the facts, with the range of axis `code`
  kFacts,      // device -> driver: the answer to kQuery
  kGrab,       // driver -> device: EVIOCGRAB (value 1) or its release (0); answered kStatus
  kUpload,     // driver -> device: EVIOCSFF; answered kStatus with the effect's id
  kErase,      // driver -> device: EVIOCRMFF; answered kStatus
  kWriteFf,    // driver -> device: an EV_FF event written (play/stop an id, gain, autocenter)
  kStatus,     // device -> driver: an ioctl's answer: 0 or an errno, and a value
  // driver -> device, first: the descriptor the device answers each update (kUpload of an
  // existing id, EVIOCSFF of a new level) on, passed with the message (SCM_RIGHTS). EVIOCSFF
  // returns only once the device has taken the update; the update thread waits for that
  // answer there while the RT thread reads the events here.
  kAnswers,
};

// One input event as read(2) gives it, its time in CLOCK_MONOTONIC ns.
struct Event {
  std::uint16_t type = 0, code = 0;
  std::int32_t value = 0;
  std::int64_t time_ns = 0;
};

// The FF_CONSTANT effect of EVIOCSFF: id -1 asks for a new one.
struct Effect {
  std::int16_t id = -1;
  std::uint16_t direction = 0xC000;  // "right" (<linux/input.h>): a positive level toward +x
  std::int16_t level = 0;
  std::uint16_t length_ms = 0;  // 0: plays until stopped
};

// What the driver learns of the device at configure (EVIOCGNAME, EVIOCGID, EVIOCGABS,
// EVIOCGBIT(EV_FF), EVIOCGEFFECTS).
struct Facts {
  std::string name, phys, uniq;
  std::uint16_t bus = 0, vendor = 0, product = 0, version = 0;
  bool has_axis = false;  // the queried axis exists
  AxisRange range;
  std::int32_t value = 0;  // the axis' current value
  std::int32_t fuzz = 0;   // the kernel's filter on it: changes within this are smoothed
  bool ff_constant = false, ff_gain = false, ff_autocenter = false;
  std::int32_t ff_effects = 0;  // effects the device holds at once
};

struct Message {
  Type type = Type::kEvent;
  Event event;             // kEvent
  std::int32_t a = 0;      // kQuery: axis code; kGrab: on; kErase: id; kWriteFf: code
  std::int32_t b = 0;      // kWriteFf: value; kStatus: the value (an uploaded effect's id)
  std::int32_t error = 0;  // kStatus: 0 or an errno
  Effect effect;           // kUpload
  Facts facts;             // kFacts
};

// The largest message (kFacts with three strings of at most 255 bytes).
inline constexpr std::size_t kMaxMessage = 1024;

// Each encodes one message into `out` (cleared first; its capacity is kept, so a buffer
// reserved to kMaxMessage is never reallocated: RT-safe with such a buffer).
void encode(const Message& m, std::vector<std::uint8_t>& out);
// A message, or nothing for bytes that are not one (an unknown type, too short, too long, a
// string past the end). Never reads past `bytes`.
std::optional<Message> decode(std::span<const std::uint8_t> bytes);

// RT-safe. The fixed-size messages straight into a buffer of at least 32 bytes: their length.
std::size_t encode_event(const Event& e, std::span<std::uint8_t> out) noexcept;
std::size_t encode_upload(const Effect& e, std::span<std::uint8_t> out) noexcept;
std::size_t encode_write_ff(int code, int value, std::span<std::uint8_t> out) noexcept;

}  // namespace hapticd::drivers::evdev::wire
