// Why an ODrive axis stopped (odrive_profile.h): the sentences of its faults, and what the stop
// asks the axis to explain them - 0.5.6's controller error after CONTROLLER_FAILED, 0.6's
// disarm reason after the axis left closed loop by itself.
#include <cmath>
#include <cstdio>

#include "drivers/can/odrive_profile.h"

namespace hapticd::drivers::can {

void OdriveAxis::read_controller_error(const CanFault& latched) noexcept {
  // CONTROLLER_FAILED says only that controller.error is set; 0.5.6 answers
  // Get_Controller_Error (can_simple.cpp), earlier 0.5 releases stay silent.
  if (!link_.is_open() || firmware_ != odrive::Firmware::k05 ||
      latched.kind != CanFaultKind::kAxisError ||
      (latched.code & odrive::overspeed_error_bits(firmware_)) == 0) {
    return;
  }
  try {
    link_.send(odrive::request(node_.node_id, odrive::kGetControllerError, 8),
               "Get_Controller_Error");
    link_.await(
        settings_.sdo_timeout_ms,
        [&](const CanFrame& f) {
          if (f.id != id_base_ + odrive::kGetControllerError) return false;
          controller_error_ = odrive::decode_controller_error(f);
          return controller_error_.has_value();
        },
        nullptr);
  } catch (...) {
    // The description falls back on the last velocity the axis reported.
  }
}

// 0.6 keeps why it disarmed in Get_Error's disarm reason, until Clear_Errors: the heartbeat
// may already say IDLE without an error (a short DC-bus dip). The RT path asked; the answer
// may be queued already.
void OdriveAxis::read_error_status(const CanFault& latched) noexcept {
  if (!link_.is_open() || firmware_ != odrive::Firmware::k06 || error_status_ ||
      (latched.kind != CanFaultKind::kAxisStateChanged &&
       latched.kind != CanFaultKind::kAxisError)) {
    return;
  }
  try {
    if (!error_requested_) {
      link_.send(odrive::request(node_.node_id, odrive::kGetError, 8), "Get_Error");
      error_requested_ = true;
    }
    link_.await(
        settings_.sdo_timeout_ms,
        [&](const CanFrame& f) {
          if (f.id != id_base_ + odrive::kGetError) return false;
          error_status_ = odrive::decode_error_status(f);
          return error_status_.has_value();
        },
        nullptr);
  } catch (...) {
    // The description says the reason was not read back.
  }
}

std::string OdriveAxis::describe(const CanFault& f, const std::string& bus) const {
  switch (f.kind) {
    case CanFaultKind::kAxisError:
      return node_name(bus) + " reports axis error " +
             odrive::describe_axis_error(firmware_, f.code) + " (firmware " +
             std::string(to_string(firmware_)) + ")" + overspeed_text(f.code) + disarm_text(f);
    case CanFaultKind::kAxisStateChanged:
      return node_name(bus) + " left CLOSED_LOOP_CONTROL by itself: its heartbeat says " +
             std::string(odrive::axis_state_name(f.code)) + disarm_text(f);
    case CanFaultKind::kHeartbeatLost:
      return node_name(bus) + ": no heartbeat for " + std::to_string(f.code) +
             " ticks (heartbeat_timeout_ms " + std::to_string(settings_.heartbeat_timeout_ms) + ")";
    default:
      return {};  // the bus's: the device names it
  }
}

// 0.6: the disarm reason Get_Error gave (the heartbeat's axis error is what is active now).
std::string OdriveAxis::disarm_text(const CanFault& f) const {
  if (firmware_ != odrive::Firmware::k06) return {};
  if (!error_status_) {
    return error_requested_ ? "; Get_Error went unanswered within sdo_timeout_ms " +
                                  std::to_string(settings_.sdo_timeout_ms) +
                                  " ms, so why it disarmed is unknown (odrivetool: "
                                  "odrv0.axis0.disarm_reason)"
                            : std::string();
  }
  const odrive::ErrorStatus& e = *error_status_;
  if (f.kind == CanFaultKind::kAxisError && e.disarm_reason == f.code) return {};
  return "; disarm reason (Get_Error) " + odrive::describe_axis_error(firmware_, e.disarm_reason) +
         ", active errors now " + odrive::describe_axis_error(firmware_, e.active_errors);
}

// Why an axis fails in torque control though hapticd never commanded a speed: the firmware's
// own velocity limit (controller.cpp: enable_torque_mode_vel_limit clamps the torque to
// (+-vel_limit - vel) * vel_gain, enable_overspeed_error faults above vel_limit_tolerance
// times vel_limit; defaults 2 turn/s and 1.2).
std::string OdriveAxis::overspeed_text(std::uint32_t axis_error) const {
  if ((axis_error & odrive::overspeed_error_bits(firmware_)) == 0) return {};
  const OdriveSettings& o = settings_.odrive;
  const double speed = std::abs(static_cast<double>(last_speed_turns_));
  std::string text;
  bool overspeed = firmware_ == odrive::Firmware::k06;  // VELOCITY_LIMIT_VIOLATION says so
  if (controller_error_) {
    text = ": controller error " + odrive::describe_controller_error(*controller_error_);
    overspeed = (*controller_error_ & odrive::kControllerOverspeed) != 0;
  } else if (firmware_ == odrive::Firmware::k05) {
    overspeed = o.vel_limit > 0.0 && speed > o.vel_limit;
    text = overspeed ? ": OVERSPEED, by the last speed the axis reported"
                     : ": controller.error was not read back (0.5.6 answers "
                       "Get_Controller_Error; odrivetool shows axis.controller.error)";
  }
  if (!overspeed) return text;
  char numbers[128];
  std::snprintf(numbers, sizeof numbers,
                " (%.3g turn/s x %.3g; the last estimate said %.3g turn/s)", o.vel_limit,
                o.vel_limit_tolerance, speed);
  return text +
         ": in torque control the firmware faults when the axis turns faster than "
         "controller.config.vel_limit x vel_limit_tolerance" +
         (o.vel_limit > 0.0 ? std::string(numbers) : std::string(" (configured here as off)")) +
         " and brakes above vel_limit by itself; raise vel_limit, or set "
         "enable_torque_mode_vel_limit and enable_overspeed_error to False (docs/drivers/can.md)";
}

}  // namespace hapticd::drivers::can
