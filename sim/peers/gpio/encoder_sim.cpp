#include "sim/peers/gpio/encoder_sim.h"

#include <algorithm>
#include <cmath>

namespace hapticd::sim::gpio {
namespace {

constexpr std::uint8_t bit_of(dg::Line line) {
  return static_cast<std::uint8_t>(1u << static_cast<unsigned>(line));
}

}  // namespace

namespace {

DriveAxis drive_axis(const config::Config& cfg, const EncoderJoint& who) {
  if (who.mechanism == nullptr) return DriveAxis(cfg.device, cfg.loop.sample_period_s());
  return DriveAxis(cfg.device, cfg.loop.sample_period_s(), *who.mechanism,
                   static_cast<int>(who.joint));
}

}  // namespace

EncoderSim::EncoderSim(const config::Config& cfg, const dg::GpioSettings& s,
                       const EncoderJoint& who)
    : axis_(drive_axis(cfg, who)),
      s_(s),
      j_(s.joint(who.joint)),
      max_force_(cfg.device.max_force[who.joint]),
      period_ns_(cfg.loop.period_ns()),
      count_(0),
      queued_levels_(0),
      line_levels_(0) {
  // Injected edges come four times faster than the rate limit allows (1 us without one). The
  // illegal pattern's step is 4 resolutions at least, so that the pattern as a whole stays
  // below the limit at any rate (any 8 of its edges span 3 steps).
  if (s.max_edge_rate_hz > 0.0) {
    fast_ns_ = std::max<std::int64_t>(1, std::llround(0.25e9 / s.max_edge_rate_hz));
    pattern_step_ns_ = std::max(pattern_step_ns_, 16 * fast_ns_);
  }
  count_ = encoder_count();
  const std::uint8_t st = dg::state_of_count(count_);
  std::uint8_t levels =
      raw(dg::Line::kA, (st & dg::kBitA) != 0) | raw(dg::Line::kB, (st & dg::kBitB) != 0);
  if (j_.line_index) levels |= raw(dg::Line::kIndex, count_ == j_.index_count);
  if (j_.line_fault) levels |= raw(dg::Line::kFault, false);
  queued_levels_ = line_levels_ = levels;
}

// The encoder as mounted: counting down as x grows when the driver's counts_per_unit is
// negative (the sim's encoder resolution is its magnitude).
std::int64_t EncoderSim::encoder_count() noexcept {
  const std::int64_t c = axis_.encoder_counts();
  return j_.counts_per_unit < 0.0 ? -c : c;
}

// The raw bit for `line` at logical level `logical` (active-low inverts).
std::uint8_t EncoderSim::raw(dg::Line line, bool logical) const noexcept {
  const bool active_low = line == dg::Line::kFault ? s_.fault_active_low : s_.encoder_active_low;
  return logical != active_low ? bit_of(line) : 0;
}

std::uint8_t EncoderSim::raw_levels() const noexcept { return line_levels_; }

// The bridge drives while the PWM input has pulses: the force follows the duty and the
// direction line alone. The channel's enable is not looked at: a disabled channel's output is
// undefined (Linux's Documentation/driver-api/pwm.rst), and this motor driver takes the worst
// a PWM chip may do, its last duty still on the pin.
void EncoderSim::apply_output(const dg::wire::Output& out) noexcept {
  channel_enabled_ = out.pwm_enabled;
  duty_ns_ = fault_active_ ? 0 : out.duty_ns;
  if (fault_active_) return;  // a motor driver in fault keeps its bridge off
  const bool driving = out.duty_ns != 0 && out.period_ns != 0;
  if (driving != axis_.output_on()) axis_.set_output(driving);
  if (!driving) return;
  const double magnitude = static_cast<double>(out.duty_ns) / static_cast<double>(out.period_ns);
  const bool positive = out.direction_level == j_.direction_positive_high;
  axis_.hold_force((positive ? 1.0 : -1.0) * magnitude * max_force_);
}

void EncoderSim::set_fault_line(bool active, std::int64_t t_ns) {
  if (!j_.line_fault || active == fault_active_) return;
  fault_active_ = active;
  if (active) {
    axis_.set_output(false);
    duty_ns_ = 0;
  }
  queue_edge(t_ns, dg::Line::kFault, active, false);
}

void EncoderSim::queue_edge(std::int64_t due_ns, dg::Line line, bool logical, bool paced) {
  const std::uint8_t bit = bit_of(line);
  const bool level = raw(line, logical) != 0;
  queued_levels_ =
      static_cast<std::uint8_t>(level ? (queued_levels_ | bit) : (queued_levels_ & ~bit));
  queue_.push_back({due_ns, line, level, paced});
}

void EncoderSim::queue_count_edges(std::int64_t from, std::int64_t to, std::int64_t t0_ns) {
  const std::int64_t n = to > from ? to - from : from - to;
  const std::int64_t dir = to > from ? 1 : -1;
  for (std::int64_t i = 0; i < n; ++i) {
    const std::int64_t before = from + i * dir;
    const std::int64_t after = before + dir;
    const std::uint8_t s0 = dg::state_of_count(before);
    const std::uint8_t s1 = dg::state_of_count(after);
    const dg::Line line = ((s0 ^ s1) & dg::kBitA) != 0 ? dg::Line::kA : dg::Line::kB;
    const std::uint8_t bit = line == dg::Line::kA ? dg::kBitA : dg::kBitB;
    // Spread evenly over the period, as a constant velocity would.
    const std::int64_t due = t0_ns + (period_ns_ * (2 * i + 1)) / (2 * n);
    if (j_.line_index && before == j_.index_count) queue_edge(due, dg::Line::kIndex, false, true);
    queue_edge(due, line, (s1 & bit) != 0, true);
    if (j_.line_index && after == j_.index_count) queue_edge(due + 1, dg::Line::kIndex, true, true);
  }
}

void EncoderSim::step(std::int64_t t0_ns) {
  axis_.step();
  const std::int64_t next = encoder_count();
  queue_count_edges(count_, next, t0_ns);
  count_ = next;
}

void EncoderSim::inject(WireFault f, std::int64_t t_ns) {
  const std::uint8_t st = dg::state_of_count(count_);
  switch (f) {
    case WireFault::kEdgeBurst: {
      const bool a = (st & dg::kBitA) != 0;
      for (int i = 0; i < 32; ++i) {
        queue_edge(t_ns + i * fast_ns_, dg::Line::kA, (i % 2 == 0) != a, false);
      }
      return;
    }
    case WireFault::kIllegalPattern:
      // Two counts forward with A and B changing at once (1 us apart at most: within the
      // resolution even when a carrier puts them on the wires late), a step (20 ms) later back
      // the same way: the count ends where it began, but each pair is a two-bit change within
      // the resolution, while the pattern as a whole (any 8 edges span 3 steps) stays below the
      // limit.
      for (int k = 0; k < 4; ++k) {
        const std::int64_t t = t_ns + k * 2 * pattern_step_ns_;
        const std::int64_t pair = std::min<std::int64_t>(fast_ns_, 1000);
        const std::uint8_t s1 = dg::state_of_count(count_ + 1);
        const std::uint8_t s2 = dg::state_of_count(count_ + 2);
        const auto edge = [&](std::int64_t at, std::uint8_t from, std::uint8_t to) {
          const dg::Line line = ((from ^ to) & dg::kBitA) != 0 ? dg::Line::kA : dg::Line::kB;
          const std::uint8_t bit = line == dg::Line::kA ? dg::kBitA : dg::kBitB;
          queue_edge(at, line, (to & bit) != 0, false);
        };
        edge(t, st, s1);
        edge(t + pair, s1, s2);
        edge(t + pattern_step_ns_, s2, s1);
        edge(t + pattern_step_ns_ + pair, s1, st);
      }
      return;
    case WireFault::kLoseEdges:
      return;  // the carrier's business: it numbers the edges
  }
}

void EncoderSim::sent(const PendingEdge& e) noexcept {
  const std::uint8_t bit = bit_of(e.line);
  line_levels_ =
      static_cast<std::uint8_t>(e.raw_level ? (line_levels_ | bit) : (line_levels_ & ~bit));
}

JointEncoders::JointEncoders(const config::Config& cfg, const dg::GpioSettings& s) {
  if (s.joints.size() > 1) {
    mechanism_ = std::make_unique<Mechanism>(cfg.device, cfg.loop.sample_period_s());
  }
  for (std::size_t j = 0; j < s.joints.size(); ++j) {
    enc_.push_back(std::make_unique<EncoderSim>(cfg, s, EncoderJoint{j, mechanism_.get()}));
  }
}

void JointEncoders::step(std::int64_t t0_ns) {
  for (const auto& e : enc_) e->step(t0_ns);
}

dg::wire::Levels JointEncoders::levels(std::int64_t now_ns) const noexcept {
  dg::wire::Levels l;
  l.levels = enc_.front()->raw_levels();
  l.time_ns = now_ns;
  l.joint_count = enc_.size();
  for (std::size_t j = 1; j < enc_.size(); ++j) l.others[j - 1] = enc_[j]->raw_levels();
  return l;
}

double JointEncoders::applied_force() const noexcept {
  double largest = 0.0;
  for (const auto& e : enc_) {
    if (std::abs(e->applied_force()) > std::abs(largest)) largest = e->applied_force();
  }
  return largest;
}

bool JointEncoders::output_on() const noexcept {
  return std::any_of(enc_.begin(), enc_.end(), [](const auto& e) { return e->output_on(); });
}

bool JointEncoders::channel_enabled() const noexcept {
  return std::all_of(enc_.begin(), enc_.end(), [](const auto& e) { return e->channel_enabled(); });
}

}  // namespace hapticd::sim::gpio
