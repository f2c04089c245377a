#include "sim/peers/hid/hid_firmware.h"

#include <cmath>
#include <stdexcept>

#include "config/config_loader.h"
#include "kinematics/kinematics.h"
#include "sim/replay_log.h"

namespace hapticd::sim::hid {
namespace {

SimAxis make_axis(const config::Config& cfg) {
  std::vector<double> replay;
  if (cfg.device.sim.op.kind == config::OperatorSpec::Kind::kReplay) {
    replay = load_replay_positions(cfg);
  }
  try {
    return SimAxis(cfg.device, cfg.loop.sample_period_s(), std::move(replay));
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError({cfg.locate("device.sim") + ": device.sim: " + e.what()});
  }
}

std::unique_ptr<Mechanism> make_mechanism(const config::Config& cfg) {
  if (kinematics::joint_count(cfg.device.kinematics) == 1) return nullptr;
  try {
    return std::make_unique<Mechanism>(cfg.device, cfg.loop.sample_period_s());
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError({cfg.locate("device.sim") + ": device.sim: " + e.what()});
  }
}

}  // namespace

HidFirmware::HidFirmware(const config::Config& cfg, int link_delay_samples)
    : axis_(make_axis(cfg)),
      mechanism_(make_mechanism(cfg)),
      fifo_(static_cast<std::size_t>(std::max(0, link_delay_samples)) + 1, encoders()) {}

std::array<double, base::kMaxJoints> HidFirmware::encoders() noexcept {
  std::array<double, base::kMaxJoints> e{};
  if (!mechanism_) {
    e[0] = axis_.encoder_position();
    return e;
  }
  for (int j = 0; j < mechanism_->joints(); ++j) e[j] = mechanism_->encoder_position(j);
  return e;
}

void HidFirmware::publish() noexcept {
  if (!mechanism_) {
    felt_.publish(axis_);
    return;
  }
  double felt = 0.0;
  for (int j = 0; j < mechanism_->joints(); ++j) {
    felt = std::max(felt, std::abs(mechanism_->held_torque(j)));
  }
  felt_.publish(felt, mechanism_->output_on(0));
}

void HidFirmware::set_output(bool on) noexcept {
  if (mechanism_) {
    for (int j = 0; j < mechanism_->joints(); ++j) mechanism_->set_output(j, on);
  } else {
    axis_.set_output(on);
  }
  publish();
}

void HidFirmware::lose_host() noexcept { set_output(false); }

void HidFirmware::step(std::span<const double> forces) noexcept {
  hold(forces);
  if (mechanism_) {
    mechanism_->step();
  } else {
    axis_.step();
  }
  fifo_[fifo_head_] = encoders();  // the newest replaces the oldest
  fifo_head_ = (fifo_head_ + 1) % fifo_.size();
}

void HidFirmware::hold(std::span<const double> forces) noexcept {
  if (mechanism_) {
    for (int j = 0; j < mechanism_->joints(); ++j) {
      const auto i = static_cast<std::size_t>(j);
      mechanism_->hold_torque(j, i < forces.size() ? forces[i] : 0.0);
    }
  } else {
    axis_.hold_force(forces.front());
  }
  publish();
}

bool HidFirmware::check_watchdog(std::chrono::steady_clock::time_point now) noexcept {
  const double silent_ms = std::chrono::duration<double, std::milli>(now - last_heard_).count();
  const double limit = watchdog_ms();
  if (!amplifier_on() || limit <= 0.0 || silent_ms <= limit) return false;
  lose_host();
  trips_.fetch_add(1);
  return true;
}

std::uint32_t HidFirmware::next_sequence() noexcept {
  // Fifty reports lost on the way: far beyond the one or two a late USB frame costs, so a test
  // on a jittery machine can set safety.sequence_gap_fault between the two.
  if (faults_.take(PeerFault::kSkipSequence)) sequence_ += kSkippedReports;
  return sequence_++;
}

bool HidFirmware::inject(PeerFault fault) noexcept {
  if (!faults_.inject(fault)) return false;                  // kTransportFault is the transport's
  if (fault == PeerFault::kDeviceFault) felt_.drop_force();  // a faulted drive stops at once
  return true;
}

}  // namespace hapticd::sim::hid
