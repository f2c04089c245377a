// The simulated device in-process, behind the Device seam: a SimAxis advanced one sample
// period per read() with the force last written (zero while output is disabled, like an
// amplifier that is off), or as many periods as the loop says passed when it skipped some: the
// sim lives through a stall as a real device does. No transport, so no transport delay; the
// sample carries the count of reads as its sequence number. It is its own loopback peer
// (SimSelfPeer), so the conformance suite can inject each fault class into it like into any
// other peer.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "config/config.h"
#include "drivers/device.h"
#include "sim/joint_plant.h"
#include "sim/mechanism.h"
#include "sim/peers/loopback_peer.h"
#include "sim/peers/peer_state.h"
#include "sim/sim_axis.h"

namespace hapticd::sim {

class SimDevice final : public hapticd::Device {
 public:
  // PositionSample::status bit set while output is enabled.
  static constexpr std::uint32_t kStatusOutputEnabled = 1u << 0;
  // ... and set with a device fault (the injected kDeviceFault); also its fault code.
  static constexpr std::uint32_t kStatusFault = 1u << 1;

  // Throws std::invalid_argument on a bad configuration (see SimAxis).
  SimDevice(const config::DeviceConfig& config, double sample_period_s,
            std::vector<double> replay_positions = {});

  std::string_view driver_name() const noexcept override { return "sim"; }
  const SimAxis& axis() const noexcept { return axis_; }
  // The mechanism of a device of several joints (device.kinematics); null for one joint.
  const JointPlant* joint_plant() const noexcept { return joints_ ? &joints_->plant() : nullptr; }
  // Any thread: make the next reads or writes fail the way `fault` says.
  bool inject(PeerFault fault) noexcept { return faults_.inject(fault); }

 protected:
  // Back to the configured initial state at t = 0, output disabled, command zero.
  DeviceInfo on_configure() override;
  void on_enable() override;
  void on_disable() noexcept override;
  void on_close() noexcept override {}
  // RT-safe: called every tick. The first call after configure() samples the initial state;
  // each later one first advances the plant read_periods() with the force last written.
  IoStatus on_read(std::span<PositionSample> samples) noexcept override;
  // RT-safe: called every tick. Stores the command for the next period, unclamped
  // (saturation is the controller's job).
  IoStatus on_write(std::span<const double> forces) noexcept override;
  std::string describe(const DeviceFault& fault) const override;

 private:
  // RT-safe: called every tick. on_read for several joints: one period on with the torques
  // held, then each joint's encoder, the faults injected as one joint's.
  IoStatus read_joints(std::span<PositionSample> samples) noexcept;

  SimAxis axis_;
  std::unique_ptr<Mechanism> joints_;  // several joints: the mechanism, else null
  bool output_on_ = false;
  bool first_read_ = true;
  std::uint64_t sequence_ = 0;
  FaultFlags<PeerFault> faults_{PeerFault::kStopAnswering, PeerFault::kSkipSequence,
                                PeerFault::kDeviceFault, PeerFault::kTransportFault};
};

// The sim device seen as its own peer: what the plant feels, and fault injection.
class SimSelfPeer final : public LoopbackPeer {
 public:
  explicit SimSelfPeer(SimDevice& device) : device_(device) {}
  void service() override {}
  int fd() const noexcept override { return -1; }
  double applied_force() const noexcept override { return device_.axis().held_force(); }
  bool output_on() const noexcept override { return device_.axis().output_on(); }
  const Plant& plant() const noexcept override { return device_.axis().plant(); }
  bool inject(PeerFault fault) noexcept override { return device_.inject(fault); }

 private:
  SimDevice& device_;
};

}  // namespace hapticd::sim
