#include "drivers/gpio/quadrature_decoder.h"

#include <cmath>
#include <limits>

namespace hapticd::drivers::gpio {
namespace {

// The forward sequence of (A, B) as state values (bit 0 A, bit 1 B): 00, 10, 11, 01.
constexpr std::array<std::uint8_t, 4> kSequence = {0, kBitA, kBitA | kBitB, kBitB};
// Position of each state value in that sequence.
constexpr std::array<std::uint8_t, 4> kPosition = {0, 1, 3, 2};

constexpr std::uint8_t kBitIndex = 1u << 2;

}  // namespace

Transition transition(std::uint8_t from, std::uint8_t to) noexcept {
  const unsigned d = (kPosition[to & 3u] + 4u - kPosition[from & 3u]) & 3u;
  switch (d) {
    case 0:
      return Transition::kNone;
    case 1:
      return Transition::kForward;
    case 3:
      return Transition::kBackward;
    default:
      return Transition::kIllegal;  // both bits: the direction is unknowable
  }
}

std::uint8_t state_of_count(std::int64_t count) noexcept {
  return kSequence[static_cast<std::uint64_t>(count) & 3u];  // mod 4, negative counts too
}

QuadratureDecoder::QuadratureDecoder(const DecoderConfig& config) noexcept : config_(config) {
  if (config_.max_edge_rate_hz > 0.0 && std::isfinite(config_.max_edge_rate_hz)) {
    min_interval_ns_ = std::llround(1e9 / config_.max_edge_rate_hz);
  }
  reset(0);
}

void QuadratureDecoder::reset(std::uint8_t levels) noexcept {
  count_ = static_cast<std::uint64_t>(config_.start_count);
  state_ = levels & (kBitA | kBitB);
  index_level_ = (levels & kBitIndex) != 0;
  state_before_last_ = state_;
  have_last_ = false;
  last_ns_ = 0;
  window_.fill(0);
  edges_ = repeated_ = illegal_ = out_of_order_ = lost_ = index_hits_ = 0;
  rate_exceeded_ = false;
  exceeded_rate_hz_ = 0.0;
}

void QuadratureDecoder::check_rate(std::int64_t t) noexcept {
  if (min_interval_ns_ == 0) return;
  std::int64_t& slot = window_[edges_ % kRateWindow];
  if (edges_ >= static_cast<std::uint64_t>(kRateWindow)) {
    const std::int64_t span = t - slot;  // kRateWindow intervals
    if (span < kRateWindow * min_interval_ns_) {
      rate_exceeded_ = true;
      const double rate = span > 0 ? kRateWindow * 1e9 / static_cast<double>(span)
                                   : std::numeric_limits<double>::infinity();
      if (rate > exceeded_rate_hz_) exceeded_rate_hz_ = rate;
    }
  }
  slot = t;
}

void QuadratureDecoder::apply_ab(const Edge& edge) noexcept {
  const std::uint8_t bit = edge.line == Line::kA ? kBitA : kBitB;
  check_rate(edge.time_ns);
  ++edges_;
  if (have_last_ && edge.time_ns < last_ns_) ++out_of_order_;
  const std::uint8_t next = edge.level ? (state_ | bit) : (state_ & ~bit);
  if (next == state_) {
    ++repeated_;  // the opposite edge never came: the line changed twice, net nothing
  } else {
    // Both bits changed within one resolution interval: what a decoder sampling at the rate
    // limit would see as (A, B) jumping two steps at once.
    if (min_interval_ns_ != 0 && have_last_ && edge.line != last_line_ &&
        edge.time_ns - last_ns_ < min_interval_ns_ &&
        transition(state_before_last_, next) == Transition::kIllegal) {
      ++illegal_;
    }
    count_ += static_cast<std::uint64_t>(static_cast<std::int64_t>(transition(state_, next)));
    state_before_last_ = state_;
    state_ = next;
  }
  last_line_ = edge.line;
  last_ns_ = edge.time_ns;
  have_last_ = true;
}

void QuadratureDecoder::apply(const Edge& edge) noexcept {
  switch (edge.line) {
    case Line::kA:
    case Line::kB:
      apply_ab(edge);
      return;
    case Line::kIndex:
      if (config_.has_index && edge.level && !index_level_) {
        count_ = static_cast<std::uint64_t>(config_.index_count);
        ++index_hits_;
      }
      index_level_ = edge.level;
      return;
    case Line::kFault:
      return;  // the device's business, not the count's
  }
}

void QuadratureDecoder::observe(std::uint8_t levels) noexcept {
  const std::uint8_t seen = levels & (kBitA | kBitB);
  const Transition t = transition(state_, seen);
  if (t == Transition::kNone) return;
  if (t == Transition::kIllegal) {
    ++illegal_;  // two edges missed, direction unknown: the count is left alone
  } else {
    ++lost_;  // one edge whose event never came; its direction is known
    count_ += static_cast<std::uint64_t>(static_cast<std::int64_t>(t));
  }
  state_before_last_ = state_;
  state_ = seen;
}

void QuadratureDecoder::add_lost(std::uint64_t edges) noexcept { lost_ += edges; }

}  // namespace hapticd::drivers::gpio
