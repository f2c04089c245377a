#include "sim/peers/can/odrive_peer.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "base/clock.h"

namespace hapticd::sim {
namespace {

using drivers::can::CanFrame;
namespace odrive = drivers::can::odrive;

}  // namespace

OdrivePeer::OdrivePeer(const config::Config& cfg, drivers::can::CanSocket socket, bool realtime,
                       const SharedJoint& joint)
    : CanPeerBase(cfg, std::move(socket), realtime, {}, joint),
      node_(settings_.nodes.front().node_id),
      firmware_(settings_.odrive.detect_firmware ? odrive::Firmware::k06
                                                 : settings_.odrive.firmware),
      watchdog_timeout_s_(settings_.odrive.watchdog_timeout_s) {
  if (firmware_ == odrive::Firmware::k06) can_faults_.allow(CanPeerFault::kDisarm);
  publish();
}

std::uint32_t OdrivePeer::fault_error() const noexcept {
  return firmware_ == odrive::Firmware::k05 ? 0x40u : 0x1000u;
}

void OdrivePeer::send_heartbeat() {
  if (can_faults_.active(CanPeerFault::kStopHeartbeat)) return;
  send(odrive::heartbeat(node_, {axis_error_, state_.load(), 0}));
}

void OdrivePeer::set_state(std::uint8_t state) {
  const bool on = state == odrive::kAxisClosedLoop;
  if (on != (state_.load() == odrive::kAxisClosedLoop)) axis_.set_output(on);
  state_.store(state);
  send_heartbeat();  // the simulation says so at once; a real axis at its next heartbeat
}

void OdrivePeer::disarm(std::uint32_t reason, bool stays_active) {
  if (stays_active) axis_error_ |= reason;
  if (firmware_ == odrive::Firmware::k06) disarm_reason_ |= reason;
  set_state(odrive::kAxisIdle);
}

void OdrivePeer::take_disarm() {
  // The dip is over before the next heartbeat: nothing stays active.
  if (can_faults_.take(CanPeerFault::kDisarm)) disarm(kDcBusUnderVoltage, false);
}

void OdrivePeer::apply_device_fault() { disarm(fault_error(), true); }

void OdrivePeer::on_bus_lost() {
  // A real axis notices when its watchdog expires; the simulation reacts at once.
  disarm(odrive::watchdog_error_bit(firmware_), true);
}

void OdrivePeer::trigger() {
  // One period has passed with the torque held so far; the newest command acts from now on.
  if (stepped_) axis_.step();
  stepped_ = true;
  ++triggers_;
  take_disarm();
  const bool torque_mode =
      control_mode_ == odrive::kControlModeTorque && input_mode_ == odrive::kInputModePassthrough;
  if (state_.load() == odrive::kAxisClosedLoop && torque_mode) {
    axis_.hold_force(static_cast<double>(input_torque_) / settings_.nodes.front().torque_per_force);
  }
  const bool cyclic = settings_.odrive.position_source == drivers::can::PositionSource::kCyclic;
  const auto every = static_cast<std::uint64_t>(
      cyclic ? std::max(1.0, std::round(settings_.odrive.cyclic_period_ms * 1e-3 / period_s_)) : 1);
  if (!faults_.active(PeerFault::kStopAnswering) && triggers_ % every == 0) {
    const double turns = axis_.encoder_position() / settings_.nodes.front().position_per_unit;
    const double speed = axis_.velocity() / settings_.nodes.front().position_per_unit;
    CanFrame f =
        odrive::encoder_estimates(node_, {static_cast<float>(turns), static_cast<float>(speed)});
    if (can_faults_.take(CanPeerFault::kWrongLengthPdo)) f.len = 6;
    send(f);
  }
  if (can_faults_.active(CanPeerFault::kUnknownIds))
    send(drivers::can::make_frame(odrive::frame_id(node_, 0x1E), 2));
  if (!realtime_) {
    const auto hb = static_cast<std::uint64_t>(
        std::max(1.0, std::round(settings_.odrive.heartbeat_period_ms * 1e-3 / period_s_)));
    if (triggers_ % hb == 0) send_heartbeat();
  }
}

void OdrivePeer::on_command(std::uint8_t command, const CanFrame& f) {
  switch (command) {
    case odrive::kSetAxisState:
      if (f.len >= 4) {
        const std::uint32_t requested = drivers::can::get_u32(f, 0);
        // Closed loop only without an error, as the firmware refuses it otherwise.
        if (requested == odrive::kAxisIdle ||
            (requested == odrive::kAxisClosedLoop && axis_error_ == 0)) {
          set_state(static_cast<std::uint8_t>(requested));
        } else {
          send_heartbeat();
        }
      }
      break;
    case odrive::kSetControllerMode:
      if (f.len == 8) {
        control_mode_ = drivers::can::get_u32(f, 0);
        input_mode_ = drivers::can::get_u32(f, 4);
      }
      break;
    case odrive::kSetInputTorque:
      if (f.len >= 4) input_torque_ = drivers::can::get_f32(f, 0);
      if (settings_.odrive.position_source == drivers::can::PositionSource::kCyclic) trigger();
      if (state_.load() != odrive::kAxisClosedLoop) axis_.hold_force(0.0);
      break;
    case odrive::kClearErrors:
      axis_error_ = 0;
      disarm_reason_ = 0;
      send_heartbeat();
      break;
    case odrive::kRxSdo:
      if (const auto r = odrive::decode_rx_sdo(f); r && firmware_ == odrive::Firmware::k06) {
        if (r->write) {
          endpoints_[r->endpoint] = r->value;
          if (r->endpoint == settings_.odrive.watchdog_timeout_endpoint) {
            float t;
            std::memcpy(&t, &r->value, sizeof t);
            watchdog_timeout_s_ = static_cast<double>(t);  // the wire carries a float
          }
        } else {
          send(odrive::tx_sdo(node_, {r->endpoint, endpoints_[r->endpoint]}));
        }
      }
      break;
    default:
      break;
  }
}

void OdrivePeer::handle(const CanFrame& f) {
  if (f.extended || odrive::node_of(f.id) != node_) return;
  if (realtime_) last_frame_ns_ = base::monotonic_ns();  // every frame feeds the watchdog
  const std::uint8_t command = odrive::command_of(f.id);
  if (f.rtr) {
    if (command == odrive::kGetEncoderEstimates) {
      if (settings_.odrive.position_source == drivers::can::PositionSource::kRequest) trigger();
    } else if (command == odrive::kGetVersion && firmware_ == odrive::Firmware::k06) {
      send(odrive::version_frame(node_, {2, 4, 4, 58, 0, 6, 10}));
    } else if (command == odrive::kHeartbeat) {
      send_heartbeat();
    } else if (command == odrive::kGetError) {
      error_requests_.fetch_add(1);
      if (firmware_ == odrive::Firmware::k06) {
        send(odrive::error_status(node_, {axis_error_, disarm_reason_}));
      }
    }
    return;
  }
  on_command(command, f);
}

void OdrivePeer::on_clock(std::int64_t now) {
  take_disarm();
  if (now - last_heartbeat_ns_ >= settings_.odrive.heartbeat_period_ms * 1'000'000LL) {
    last_heartbeat_ns_ = now;
    send_heartbeat();
  }
  if (state_.load() == odrive::kAxisClosedLoop && last_frame_ns_ != 0 &&
      now - last_frame_ns_ > static_cast<std::int64_t>(watchdog_timeout_s_ * 1e9)) {
    disarm(odrive::watchdog_error_bit(firmware_), true);
  }
}

}  // namespace hapticd::sim
