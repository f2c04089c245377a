// The GPIO driver's only user of libgpiod: the encoder's input lines (A, B, optional index and
// motor-driver fault) requested for both-edge events with kernel timestamps, and the direction
// output line. One implementation per libgpiod API, chosen at build time by the version
// pkg-config finds: gpiod_lines_v1.cpp (libgpiod 1.6, Debian 12: one event descriptor per
// line, no sequence numbers) or gpiod_lines_v2.cpp (libgpiod 2.x, Debian 13: one line request
// with an edge-event buffer and per-event sequence numbers that reveal kernel-side overflow).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "drivers/gpio/quadrature_decoder.h"

namespace hapticd::drivers::gpio {

// One joint's lines on a chip, and the level its direction output starts at.
struct LineOffsets {
  unsigned a = 0;
  unsigned b = 1;
  std::optional<unsigned> index;
  std::optional<unsigned> fault;
  unsigned direction = 2;
  std::uint8_t joint = 0;
  bool direction_level = false;
};

class GpiodLines {
 public:
  GpiodLines();
  ~GpiodLines();
  GpiodLines(const GpiodLines&) = delete;
  GpiodLines& operator=(const GpiodLines&) = delete;

  // Not RT-safe. `chip` is a path ("/dev/gpiochip0"), a name ("gpiochip0") or a label;
  // `joints` every joint whose lines are on it (2.x: all in one line request). Each direction
  // line starts at its direction_level. Throws DeviceError naming the chip, the line and the
  // reason (busy: who holds it; EACCES: the udev rule).
  void open(const std::string& chip, std::span<const LineOffsets> joints);
  void close() noexcept;
  // Not RT-safe. Raw levels (wire::kLevel* bits) of the input lines, into levels[joint] of
  // each joint on the chip.
  void read_levels(std::span<std::uint8_t> levels);
  std::string describe() const;

  // RT-safe. Every pending edge (raw levels, Edge::joint set) without blocking, each joint's
  // oldest first, up to out.size(); lost[joint] gets the events the kernel dropped (2.x:
  // sequence gaps, which the kernel numbers per request: a gap counts against every joint on
  // the chip, whose edge it was being unknowable; 1.6 cannot tell). 0 or errno.
  int read_events(std::span<Edge> out, std::size_t& count, std::span<std::uint64_t> lost) noexcept;
  // RT-safe. Joint `joint`'s direction line. 0 or errno.
  int set_direction(std::uint8_t joint, bool level) noexcept;

  // "libgpiod 1.6.3 (API 1)" or "libgpiod 2.2.1 (API 2)".
  static std::string api();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hapticd::drivers::gpio
