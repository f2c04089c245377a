// The x4 quadrature decoder of the GPIO driver: pure (no OS headers), fed with timestamped
// edges merged from the encoder's two lines (and the optional index line), as the kernel
// reports them. Every edge of A or B moves the count by one; which way follows from the Gray
// sequence of the two-bit state (A, B):
//
//   forward:  (0,0) -> (1,0) -> (1,1) -> (0,1) -> (0,0)        (A leads B)
//
// An edge event says which line changed and to which level. Three things show that edges were
// missed, and each is counted (missed_edges()) rather than guessed at:
//   - a repeated level: an edge to the level the line already has (the opposite edge was lost,
//     or the kernel coalesced two edges of a glitch: it reads the level late);
//   - an illegal transition: both bits changed within one resolution interval, 1/max_edge_rate
//     (a decoder sampling at max_edge_rate would have seen both bits change at once: the
//     direction is unknowable), or two lines' levels that disagree with the count (observe());
//   - an edge older than the one before it (the merge across lines lost the order).
// Lost events the kernel reports (the 2.x API's sequence numbers) are added with add_lost().
// Edges faster than max_edge_rate, sustained over kRateWindow edges, latch rate_exceeded().
// The count is a 64-bit two's-complement counter that wraps (no undefined overflow).
#pragma once

#include <array>
#include <cstdint>

namespace hapticd::drivers::gpio {

enum class Line : std::uint8_t { kA = 0, kB = 1, kIndex = 2, kFault = 3 };
inline constexpr int kLineCount = 4;

struct Edge {
  std::int64_t time_ns = 0;  // CLOCK_MONOTONIC of the edge (the kernel's timestamp)
  std::uint32_t seqno = 0;   // the transport's event sequence number (0 where it has none)
  Line line = Line::kA;
  bool level = false;      // the line's logical level after the edge (active-low applied)
  std::uint8_t joint = 0;  // whose encoder or motor driver (device.gpio.joints[joint])
};

// Bits of a two-bit encoder state.
inline constexpr std::uint8_t kBitA = 1u << 0;
inline constexpr std::uint8_t kBitB = 1u << 1;

enum class Transition : std::int8_t { kNone = 0, kForward = 1, kBackward = -1, kIllegal = 2 };

// The whole x4 table: from one (A, B) state to another (bits kBitA, kBitB; higher bits ignored).
Transition transition(std::uint8_t from, std::uint8_t to) noexcept;
// The state a count sits in (count mod 4 along the forward sequence), and back.
std::uint8_t state_of_count(std::int64_t count) noexcept;

struct DecoderConfig {
  std::int64_t start_count = 0;   // the count at reset()
  bool has_index = false;         // an index line re-zeroes the count
  std::int64_t index_count = 0;   // the count the index's rising edge sets
  double max_edge_rate_hz = 0.0;  // A/B edges per second; 0: no limit and no resolution check
};

class QuadratureDecoder {
 public:
  // Edges over which a rate above max_edge_rate must be sustained to latch rate_exceeded().
  static constexpr int kRateWindow = 8;

  explicit QuadratureDecoder(const DecoderConfig& config) noexcept;

  // Starts over at start_count with the lines at `levels` (kBitA | kBitB | index bit 2).
  void reset(std::uint8_t levels) noexcept;
  // RT-safe. One edge, in time order.
  void apply(const Edge& edge) noexcept;
  // RT-safe. The levels of A and B read directly (kBitA, kBitB): a one-bit difference is an
  // edge whose event never came (applied, counted missed); two bits is an illegal transition.
  void observe(std::uint8_t levels) noexcept;
  // RT-safe. Edges the transport says it lost (kernel buffer overflow).
  void add_lost(std::uint64_t edges) noexcept;

  std::int64_t count() const noexcept { return static_cast<std::int64_t>(count_); }
  std::uint8_t state() const noexcept { return state_; }
  bool index_level() const noexcept { return index_level_; }
  std::int64_t last_edge_ns() const noexcept { return last_ns_; }

  std::uint64_t edges() const noexcept { return edges_; }  // A/B edges applied
  std::uint64_t repeated_levels() const noexcept { return repeated_; }
  std::uint64_t illegal_transitions() const noexcept { return illegal_; }
  std::uint64_t out_of_order() const noexcept { return out_of_order_; }
  std::uint64_t lost() const noexcept { return lost_; }
  std::uint64_t missed_edges() const noexcept {
    return repeated_ + illegal_ + out_of_order_ + lost_;
  }
  std::uint64_t index_hits() const noexcept { return index_hits_; }
  bool rate_exceeded() const noexcept { return rate_exceeded_; }
  // The highest rate seen over a window that exceeded the limit (edges/s), for the message.
  double exceeded_rate_hz() const noexcept { return exceeded_rate_hz_; }

 private:
  void apply_ab(const Edge& edge) noexcept;
  void check_rate(std::int64_t t) noexcept;

  DecoderConfig config_;
  std::int64_t min_interval_ns_ = 0;  // 1/max_edge_rate: the resolution
  std::uint64_t count_ = 0;           // two's complement: wraps by definition
  std::uint8_t state_ = 0;
  bool index_level_ = false;
  // The A/B edge before this one: for the resolution check.
  std::uint8_t state_before_last_ = 0;
  Line last_line_ = Line::kA;
  bool have_last_ = false;
  std::int64_t last_ns_ = 0;
  std::array<std::int64_t, kRateWindow> window_{};  // times of the last kRateWindow A/B edges
  std::uint64_t edges_ = 0;
  std::uint64_t repeated_ = 0;
  std::uint64_t illegal_ = 0;
  std::uint64_t out_of_order_ = 0;
  std::uint64_t lost_ = 0;
  std::uint64_t index_hits_ = 0;
  bool rate_exceeded_ = false;
  double exceeded_rate_hz_ = 0.0;
};

}  // namespace hapticd::drivers::gpio
