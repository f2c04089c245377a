// The GPIO driver's loopback wire format: what the kernel carries between hapticd and the
// hardware (edge events in; PWM duty, PWM enable and the direction line out), as messages on
// a SOCK_SEQPACKET pair, so the driver's own code runs against its peer
// (sim/peers/gpio/). Pure: no OS headers; the peer uses this same codec. Little-endian,
// fixed layouts; every decode checks the length and each field, and refuses (returns false)
// rather than guess.
//
//   driver -> peer  kHello   (1 byte)                 the driver opened the lines: send levels
//                   kOutput  (24 bytes)               one joint's PWM and direction line for
//                                                     the next period: sent once a tick for
//                                                     each joint, in joint order; the last
//                                                     joint's is the period's clock (the peer
//                                                     steps its plant on it)
//   peer -> driver  kLevels  (10 + 1 n bytes)         the lines' levels now (answer to hello):
//                                                     joint 0's, then n more joints'
//                   kEdges   (16 + 14 n bytes)        n <= kMaxEdgesPerMessage edges, and the
//                                                     time up to which the stream is complete
//
// A device of one joint sends exactly what it sent before joints existed: joint 0 is a zero
// byte where the formats had a reserved one (kOutput byte 2, an edge's line byte's high
// nibble), and kLevels has no further joints.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "drivers/gpio/quadrature_decoder.h"

namespace hapticd::drivers::gpio::wire {

enum class Type : std::uint8_t { kHello = 1, kOutput = 2, kLevels = 3, kEdges = 4 };

inline constexpr std::size_t kMaxEdgesPerMessage = 64;
inline constexpr std::size_t kHelloSize = 1;
inline constexpr std::size_t kOutputSize = 24;
inline constexpr std::size_t kLevelsSize = 10;  // one joint; +1 per further joint
inline constexpr std::size_t kEdgesHeaderSize = 16;
inline constexpr std::size_t kEdgeSize = 14;
inline constexpr std::size_t kMaxMessageSize = kEdgesHeaderSize + kMaxEdgesPerMessage * kEdgeSize;

// Line levels as bits: A, B, index, fault (raw electrical levels, before active-low).
inline constexpr std::uint8_t kLevelA = 1u << 0;
inline constexpr std::uint8_t kLevelB = 1u << 1;
inline constexpr std::uint8_t kLevelIndex = 1u << 2;
inline constexpr std::uint8_t kLevelFault = 1u << 3;

struct Output {
  std::uint64_t duty_ns = 0;
  std::uint64_t period_ns = 0;
  bool pwm_enabled = false;      // the channel's enable: always on from the driver (sysfs_pwm.h)
  bool direction_level = false;  // the direction line's electrical level
  bool inversed = false;         // PWM polarity
  std::uint8_t joint = 0;        // whose channel and direction line
};

inline constexpr std::size_t kMaxJoints = 3;  // base::kMaxJoints; the wire stays pure

struct Levels {
  std::uint8_t levels = 0;  // joint 0's kLevel* bits
  std::int64_t time_ns = 0;
  std::array<std::uint8_t, kMaxJoints - 1> others{};  // joints 1.. (joint_count - 1 of them)
  std::size_t joint_count = 1;

  std::uint8_t of(std::size_t joint) const noexcept {
    return joint == 0 ? levels : others[joint - 1];
  }
};

// An edge on the wire carries the raw level; active-low is the driver's to apply.
struct EdgesHeader {
  std::uint16_t count = 0;
  std::int64_t complete_until_ns = 0;  // no edge before this time is still to come
};

// Each encoder returns the bytes written (0 when `out` is too small).
std::size_t encode_hello(std::span<std::uint8_t> out) noexcept;
std::size_t encode_output(const Output& o, std::span<std::uint8_t> out) noexcept;
std::size_t encode_levels(const Levels& l, std::span<std::uint8_t> out) noexcept;
std::size_t encode_edges(std::int64_t complete_until_ns, std::span<const Edge> edges,
                         std::span<std::uint8_t> out) noexcept;

// The message's type, or false for an empty or unknown one.
bool peek_type(std::span<const std::uint8_t> msg, Type& type) noexcept;
bool decode_hello(std::span<const std::uint8_t> msg) noexcept;
bool decode_output(std::span<const std::uint8_t> msg, Output& o) noexcept;
bool decode_levels(std::span<const std::uint8_t> msg, Levels& l) noexcept;
// Header first; then each edge by index (< header.count). False for a wrong length, a count
// above kMaxEdgesPerMessage, a line number or level byte out of range.
bool decode_edges_header(std::span<const std::uint8_t> msg, EdgesHeader& h) noexcept;
bool decode_edge(std::span<const std::uint8_t> msg, std::size_t i, Edge& e) noexcept;

}  // namespace hapticd::drivers::gpio::wire
