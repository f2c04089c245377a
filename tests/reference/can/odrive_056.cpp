#include "reference/can/odrive_056.h"

#include <algorithm>
#include <cmath>

namespace hapticd::reference {
namespace {

// can_simple.hpp, fw-v0.5.6
constexpr std::uint32_t kNmt = 0x000;
constexpr std::uint32_t kHeartbeat = 0x001;
constexpr std::uint32_t kEstop = 0x002;
constexpr std::uint32_t kSetAxisState = 0x007;
constexpr std::uint32_t kGetEncoderEstimates = 0x009;
constexpr std::uint32_t kSetControllerModes = 0x00B;
constexpr std::uint32_t kSetInputTorque = 0x00E;
constexpr std::uint32_t kClearErrors = 0x018;
constexpr std::uint32_t kGetControllerError = 0x01D;
constexpr std::uint32_t kEstopRequested = 0x00004000;  // axis error ESTOP_REQUESTED
constexpr std::int32_t kTorqueControl = 1;

}  // namespace

Odrive056::Odrive056(const Odrive056Config& c, const PlantParameters& plant, std::int64_t now_ns)
    : c_(c),
      plant_(plant, now_ns),
      last_feed_ns_(now_ns),  // Axis::apply_config feeds the watchdog at boot
      last_heartbeat_ns_(now_ns),
      last_encoder_ns_(now_ns) {}

// One pass of ODrive::control_loop_cb for this axis: the watchdog, then the controller.
void Odrive056::control_pass(std::int64_t now_ns) {
  plant_.advance_to(now_ns);
  if (c_.enable_watchdog &&
      now_ns - last_feed_ns_ > static_cast<std::int64_t>(c_.watchdog_timeout_s * 1e9)) {
    error_.fetch_or(kWatchdogExpired);  // set again on every pass until fed
  }
  if (state_.load() == kClosedLoop && error_.load() != 0) state_.store(kIdle);  // disarmed
  if (state_.load() != kClosedLoop) {
    plant_.hold_motor_force(0.0);
    return;
  }
  if (control_mode_ != kTorqueControl) {
    unmodelled_.fetch_add(1);
    plant_.hold_motor_force(0.0);
    return;
  }
  const double vel = plant_.velocity() / c_.metres_per_turn;  // turn/s
  if (c_.enable_overspeed_error && std::abs(vel) > c_.vel_limit_tolerance * c_.vel_limit) {
    controller_error_.fetch_or(kOverspeed);
    error_.fetch_or(kControllerFailed);
    state_.store(kIdle);
    plant_.hold_motor_force(0.0);
    return;
  }
  double torque = static_cast<double>(input_torque_);
  if (c_.enable_torque_mode_vel_limit) {
    torque =
        std::clamp(torque, (-c_.vel_limit - vel) * c_.vel_gain, (c_.vel_limit - vel) * c_.vel_gain);
  }
  plant_.hold_motor_force(torque / c_.nm_per_newton);
}

void Odrive056::send_heartbeat(std::vector<Frame>& out) const {
  Frame f = make_frame((static_cast<std::uint32_t>(c_.node) << 5) | kHeartbeat, 8);
  f.put_u32(0, error_.load());
  f.data[4] = state_.load();
  f.data[5] = 0;  // motor error flags
  f.data[6] = 0;  // encoder error flags
  f.data[7] = static_cast<std::uint8_t>((controller_error_.load() != 0 ? 1 : 0) | 0x80);
  out.push_back(f);
}

Frame Odrive056::estimates() const {
  Frame f = make_frame((static_cast<std::uint32_t>(c_.node) << 5) | kGetEncoderEstimates, 8);
  f.put_f32(0, static_cast<float>(plant_.position() / c_.metres_per_turn));
  f.put_f32(4, static_cast<float>(plant_.velocity() / c_.metres_per_turn));
  return f;
}

void Odrive056::command(std::uint32_t cmd, const Frame& f, std::vector<Frame>& out) {
  switch (cmd) {
    case kNmt:
    case kHeartbeat:
      break;  // MSG_CO_NMT_CTRL, MSG_ODRIVE_HEARTBEAT: nothing (but the feed)
    case kEstop:
      error_.fetch_or(kEstopRequested);
      break;
    case kSetAxisState: {
      const auto requested = static_cast<std::int32_t>(f.u32(0));
      if (requested == kIdle) state_.store(kIdle);
      // Closed loop arms the motor; with an error latched the next pass disarms it again.
      if (requested == kClosedLoop) state_.store(error_.load() == 0 ? kClosedLoop : kIdle);
      break;
    }
    case kGetEncoderEstimates:
      if (f.rtr || f.len == 0) out.push_back(estimates());
      break;
    case kSetControllerModes:
      control_mode_ = static_cast<std::int32_t>(f.u32(0));
      input_mode_ = static_cast<std::int32_t>(f.u32(4));
      break;
    case kSetInputTorque:
      input_torque_ = f.f32(0);
      break;
    case kClearErrors:  // ODrive::clear_errors: every error of every axis
      error_.store(0);
      controller_error_.store(0);
      break;
    case kGetControllerError: {
      Frame a = make_frame((static_cast<std::uint32_t>(c_.node) << 5) | kGetControllerError, 8);
      a.put_u32(0, controller_error_.load());
      out.push_back(a);
      break;
    }
    default:
      break;
  }
}

void Odrive056::on_frame(const Frame& f, std::int64_t now_ns, std::vector<Frame>& out) {
  if ((f.id >> 5) != c_.node) return;
  last_feed_ns_ = now_ns;  // CANSimple::do_command: axis.watchdog_feed() for every command
  control_pass(now_ns);
  command(f.id & 0x1F, f, out);
  control_pass(now_ns);
}

void Odrive056::on_clock(std::int64_t now_ns, std::vector<Frame>& out) {
  control_pass(now_ns);
  // CANSimple::service_stack: each periodic message when its rate has passed.
  const auto due = [&](std::uint32_t rate_ms, std::int64_t& last) {
    if (rate_ms == 0 || now_ns - last < static_cast<std::int64_t>(rate_ms) * 1'000'000)
      return false;
    last = now_ns;
    return true;
  };
  if (due(c_.heartbeat_rate_ms, last_heartbeat_ns_)) send_heartbeat(out);
  if (due(c_.encoder_rate_ms, last_encoder_ns_)) out.push_back(estimates());
}

}  // namespace hapticd::reference
