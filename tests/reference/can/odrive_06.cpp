#include "reference/can/odrive_06.h"

namespace hapticd::reference {
namespace {

// can_simple_messages.hpp (ODriveArduino v0.10.9): cmd_id of each message.
constexpr std::uint32_t kGetVersion = 0x000;
constexpr std::uint32_t kHeartbeat = 0x001;
constexpr std::uint32_t kEstop = 0x002;
constexpr std::uint32_t kGetError = 0x003;
constexpr std::uint32_t kSetAxisState = 0x007;
constexpr std::uint32_t kGetEncoderEstimates = 0x009;
constexpr std::uint32_t kSetControllerMode = 0x00B;
constexpr std::uint32_t kSetInputTorque = 0x00E;
constexpr std::uint32_t kClearErrors = 0x018;
// ODriveEnums.h
constexpr std::uint32_t kTorqueControl = 1;
constexpr std::uint32_t kPassthrough = 1;

}  // namespace

Odrive06::Odrive06(const Odrive06Config& c, const PlantParameters& plant, std::int64_t now_ns)
    : c_(c),
      plant_(plant, now_ns),
      last_heartbeat_ns_(now_ns),
      last_encoder_ns_(now_ns),
      last_error_ns_(now_ns) {}

Frame Odrive06::message(std::uint32_t cmd) const {
  return make_frame((static_cast<std::uint32_t>(c_.node) << 5) | cmd, 8);
}

Frame Odrive06::heartbeat() const {
  Frame f = message(kHeartbeat);
  f.put_u32(0, active_.load());  // Axis_Error: the active errors (ros_odrive)
  f.data[4] = state_.load();
  f.data[5] = 0;  // Procedure_Result: SUCCESS (not modelled)
  f.data[6] = 0;  // Trajectory_Done_Flag
  return f;
}

Frame Odrive06::estimates() const {
  Frame f = message(kGetEncoderEstimates);
  f.put_f32(0, static_cast<float>(plant_.position() / c_.metres_per_turn));
  f.put_f32(4, static_cast<float>(plant_.velocity() / c_.metres_per_turn));
  return f;
}

Frame Odrive06::error_message() const {
  Frame f = message(kGetError);
  f.put_u32(0, active_.load());
  f.put_u32(4, disarm_reason_.load());
  return f;
}

// One pass of the axis: the errors present now, a disarm on any of them, the torque.
void Odrive06::control_pass(std::int64_t now_ns) {
  plant_.advance_to(now_ns);
  const std::uint32_t active = latched_ | (now_ns < dip_until_ns_ ? kDcBusUnderVoltage : 0u);
  active_.store(active);
  if (state_.load() == kClosedLoop && active != 0) {
    disarm_reason_.fetch_or(active);
    state_.store(kIdle);
  }
  if (state_.load() != kClosedLoop) {
    plant_.hold_motor_force(0.0);
    return;
  }
  if (control_mode_ != kTorqueControl || input_mode_ != kPassthrough) {
    unmodelled_.fetch_add(1);
    plant_.hold_motor_force(0.0);
    return;
  }
  plant_.hold_motor_force(static_cast<double>(input_torque_) / c_.nm_per_newton);
}

void Odrive06::request(std::uint32_t cmd, std::vector<Frame>& out) {
  switch (cmd) {
    case kGetVersion: {
      Frame f = message(kGetVersion);
      f.data[4] = c_.fw_major;
      f.data[5] = c_.fw_minor;
      f.data[6] = c_.fw_revision;
      out.push_back(f);
      break;
    }
    case kHeartbeat:
      out.push_back(heartbeat());
      break;
    case kGetError:
      error_requests_.fetch_add(1);
      out.push_back(error_message());
      break;
    case kGetEncoderEstimates:
      out.push_back(estimates());
      break;
    default:
      break;
  }
}

void Odrive06::command(std::uint32_t cmd, const Frame& f, std::vector<Frame>& out) {
  switch (cmd) {
    case kEstop:
      latched_ |= kEstopRequested;
      break;
    case kSetAxisState:
      if (f.len >= 4) {
        const std::uint32_t requested = f.u32(0);
        if (requested == kIdle) state_.store(kIdle);
        // Arming is refused while an error is active; the heartbeat says which state it is in.
        if (requested == kClosedLoop && active_.load() == 0) state_.store(kClosedLoop);
      }
      break;
    case kSetControllerMode:
      if (f.len >= 8) {
        control_mode_ = f.u32(0);
        input_mode_ = f.u32(4);
      }
      break;
    case kSetInputTorque:
      if (f.len >= 4) input_torque_ = f.f32(0);
      break;
    case kClearErrors:  // the disarm reason, and the errors whose condition is gone
      latched_ = 0;
      disarm_reason_.store(0);
      out.push_back(heartbeat());
      break;
    default:
      break;
  }
}

void Odrive06::on_frame(const Frame& f, std::int64_t now_ns, std::vector<Frame>& out) {
  if ((f.id >> 5) != c_.node) return;
  control_pass(now_ns);
  const std::uint32_t cmd = f.id & 0x1F;
  if (f.rtr) {
    request(cmd, out);
  } else {
    command(cmd, f, out);
  }
  control_pass(now_ns);
}

void Odrive06::on_clock(std::int64_t now_ns, std::vector<Frame>& out) {
  control_pass(now_ns);
  const auto due = [&](std::uint32_t rate_ms, std::int64_t& last) {
    if (rate_ms == 0 || now_ns - last < static_cast<std::int64_t>(rate_ms) * 1'000'000)
      return false;
    last = now_ns;
    return true;
  };
  if (due(c_.heartbeat_msg_rate_ms, last_heartbeat_ns_)) {
    out.push_back(heartbeat());
    if (const int ms = dip_ms_.exchange(0); ms > 0) dip_until_ns_ = now_ns + ms * 1'000'000LL;
  }
  if (due(c_.encoder_msg_rate_ms, last_encoder_ns_)) out.push_back(estimates());
  if (due(c_.error_msg_rate_ms, last_error_ns_)) out.push_back(error_message());
}

}  // namespace hapticd::reference
