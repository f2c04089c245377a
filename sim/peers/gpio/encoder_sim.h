// What sits on the far side of the GPIO driver's wires, as both GPIO peers simulate it: a
// motor driver that turns the PWM duty and the direction line into a force on the plant
// (force = +-duty/period * max_force, whatever the channel's enable says: a disabled channel's
// output is undefined, so only duty 0 stops it; off while its fault line is active), and a
// quadrature encoder (with an optional one-count index mark at index_count and an optional fault
// output) that turns the plant's motion into edges on its lines, spread over the period in which
// the motion happened. Also the faults a peer can inject on those wires. Not RT-safe; no OS calls:
// the peers (loopback_peer, kernel_peer) carry the edges. A device of several joints has one
// EncoderSim per joint, each moving its joint of one Mechanism (sim/mechanism.h) shared by all.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "drivers/gpio/gpio_settings.h"
#include "drivers/gpio/gpio_wire.h"
#include "drivers/gpio/quadrature_decoder.h"
#include "sim/mechanism.h"
#include "sim/peers/drive_axis.h"

namespace hapticd::sim::gpio {

namespace dg = hapticd::drivers::gpio;

// Faults on the GPIO wires beyond the generic PeerFault ones.
enum class WireFault {
  kEdgeBurst,       // 32 toggles of line A, 4 times faster than max_edge_rate allows (1 us
                    // apart without one)
  kIllegalPattern,  // 4 times, 40 ms apart: A and B changed at once (two steps within the
                    // resolution), 20 ms later back; at a max_edge_rate below 200 edges/s,
                    // 8 and 4 resolutions instead
  kLoseEdges,       // the next edge's sequence number skips 5 (a kernel buffer overflow)
};

// An edge waiting to be put on the wires: `due_ns` is when it happens.
struct PendingEdge {
  std::int64_t due_ns = 0;
  dg::Line line = dg::Line::kA;
  bool raw_level = false;
  bool paced = true;  // false: injected timing, not spread by the carrier's minimum spacing
};

// Who an EncoderSim is: joint `joint` of device.gpio, moving `mechanism`'s joint (null: an axis
// of its own, a device of one joint).
struct EncoderJoint {
  std::size_t joint = 0;
  Mechanism* mechanism = nullptr;
};

class EncoderSim {
 public:
  EncoderSim(const config::Config& cfg, const dg::GpioSettings& s, const EncoderJoint& who = {});

  // Raw levels of the lines now (wire::kLevel* bits).
  std::uint8_t raw_levels() const noexcept;
  // The motor driver's inputs: force held from the next step on.
  void apply_output(const dg::wire::Output& out) noexcept;
  // One period of the plant from `t0_ns`; its encoder edges are queued, spread over the period.
  void step(std::int64_t t0_ns);
  // Queue an injected pattern starting at `t_ns`; the fault line.
  void inject(WireFault f, std::int64_t t_ns);
  void set_fault_line(bool active, std::int64_t t_ns);
  bool fault_line() const noexcept { return fault_active_; }

  std::deque<PendingEdge>& queue() noexcept { return queue_; }
  // The level a queued edge leaves its line at, applied when the carrier sends it.
  void sent(const PendingEdge& e) noexcept;

  double applied_force() const noexcept { return axis_.held_force(); }
  // The duty last applied (0 while the motor driver is in fault).
  std::uint64_t duty_ns() const noexcept { return duty_ns_; }
  // The bridge drives the motor: a non-zero duty reaches it (and no fault holds it off).
  bool output_on() const noexcept { return axis_.output_on(); }
  // The PWM channel's enable as last written: what the driver did with it (the force above
  // does not depend on it).
  bool channel_enabled() const noexcept { return channel_enabled_; }
  const Plant& plant() const noexcept { return axis_.plant(); }
  std::int64_t period_ns() const noexcept { return period_ns_; }
  std::int64_t injected_spacing_ns() const noexcept { return fast_ns_; }

 private:
  void queue_count_edges(std::int64_t from, std::int64_t to, std::int64_t t0_ns);
  std::uint8_t raw(dg::Line line, bool logical) const noexcept;
  std::int64_t encoder_count() noexcept;
  void queue_edge(std::int64_t due_ns, dg::Line line, bool logical, bool paced);

  DriveAxis axis_;
  dg::GpioSettings s_;
  dg::GpioJointSettings j_;
  double max_force_;
  std::uint64_t duty_ns_ = 0;
  std::int64_t period_ns_;
  std::int64_t count_;          // the encoder's true count (the plant's), as queued
  std::uint8_t queued_levels_;  // raw levels once every queued edge is sent
  std::uint8_t line_levels_;    // raw levels as last sent (kLevel* bits)
  bool fault_active_ = false;
  bool channel_enabled_ = false;
  std::int64_t fast_ns_ = 1000;                // the spacing of injected edges
  std::int64_t pattern_step_ns_ = 20'000'000;  // the illegal pattern's step
  std::deque<PendingEdge> queue_;
};

// Every joint's EncoderSim: a device of one joint's on an axis of its own (exactly as before
// joints existed), several joints' each on its joint of one Mechanism.
class JointEncoders {
 public:
  // Throws std::invalid_argument for a mechanism (device.sim) that cannot be simulated.
  JointEncoders(const config::Config& cfg, const dg::GpioSettings& s);

  std::size_t size() const noexcept { return enc_.size(); }
  EncoderSim& operator[](std::size_t joint) noexcept { return *enc_[joint]; }
  const EncoderSim& operator[](std::size_t joint) const noexcept { return *enc_[joint]; }
  // One period from t0_ns for every joint (the mechanism steps once: Mechanism::step_joint).
  void step(std::int64_t t0_ns);
  // Every joint's raw levels, for the loopback's answer to hello.
  dg::wire::Levels levels(std::int64_t now_ns) const noexcept;

  // The largest force any joint's motor puts on the mechanism, and whether any is on: what the
  // hand can feel. The channel enabled: every joint's.
  double applied_force() const noexcept;
  bool output_on() const noexcept;
  bool channel_enabled() const noexcept;
  const Plant& plant() const noexcept { return enc_.front()->plant(); }
  // Periods simulated so far (the mechanism's, for several joints).
  std::uint64_t steps() const noexcept {
    return mechanism_ ? mechanism_->plant().steps() : plant().steps();
  }
  const JointPlant* joint_plant() const noexcept {
    return mechanism_ ? &mechanism_->plant() : nullptr;
  }

 private:
  std::unique_ptr<Mechanism> mechanism_;  // null for one joint
  std::vector<std::unique_ptr<EncoderSim>> enc_;
};

}  // namespace hapticd::sim::gpio
