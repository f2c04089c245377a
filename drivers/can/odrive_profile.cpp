// The ODrive axis: start-up, the lifecycle and the tick (odrive_faults.cpp: why it stopped).
#include "drivers/can/odrive_profile.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "base/clock.h"

namespace hapticd::drivers::can {
namespace {

using odrive::Heartbeat;

bool any_heartbeat(const Heartbeat&) { return true; }
bool idle(const Heartbeat& h) { return h.axis_error != 0 || h.axis_state == odrive::kAxisIdle; }
bool closed_loop(const Heartbeat& h) {
  return h.axis_error != 0 || h.axis_state == odrive::kAxisClosedLoop;
}
bool no_error(const Heartbeat& h) { return h.axis_error == 0; }

std::uint32_t float_bits(float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}

}  // namespace

std::string OdriveAxis::node_name(const std::string& bus) const {
  return "can: odrive node " + std::to_string(node_.node_id) + " on " + bus;
}

Heartbeat OdriveAxis::await_heartbeat(int timeout_ms, const std::string& waiting_for,
                                      bool (*accept)(const Heartbeat&)) {
  Heartbeat got;
  const bool seen = link_.await(
      timeout_ms,
      [&](const CanFrame& f) {
        if (f.id != id_base_ + odrive::kHeartbeat || f.rtr) return false;
        const auto h = odrive::decode_heartbeat(f);
        if (!h) return false;
        got = *h;
        return accept(got);
      },
      [this](const CanFrame& f) { note_unsolicited(f); });
  if (!seen) {
    throw DeviceError(
        node_name() + ": no heartbeat " + waiting_for + " within " + std::to_string(timeout_ms) +
        " ms" +
        (accept == &any_heartbeat
             ? std::string(" (node id, bitrate, wiring, power, ") +
                   (firmware_ == odrive::Firmware::k05 ? "axis.config.can.heartbeat_rate_ms"
                                                       : "axis.config.can.heartbeat_msg_rate_ms") +
                   ")"
             : ", last state " + std::string(odrive::axis_state_name(got.axis_state))));
  }
  return got;
}

void OdriveAxis::note_unsolicited(const CanFrame& f) {
  if (!f.rtr && f.id == id_base_ + odrive::kGetEncoderEstimates) ++unsolicited_estimates_;
}

void OdriveAxis::feed_watchdog() {
  if (!link_.is_open()) return;
  // A remote request for the heartbeat: 0.5 does nothing with it but feed the watchdog
  // (can_simple.cpp, MSG_ODRIVE_HEARTBEAT), 0.6 answers it with a heartbeat.
  const double period_ms = std::clamp(settings_.odrive.watchdog_timeout_s * 1e3 / 4.0, 1.0, 50.0);
  feeder_.start(link_.fd(), {{odrive::request(node_.node_id, odrive::kHeartbeat, 8),
                              static_cast<std::int64_t>(period_ms * 1e6), 0}});
}

Heartbeat OdriveAxis::clear_expired_watchdog(Heartbeat h) {
  const std::uint32_t expired = odrive::watchdog_error_bit(firmware_);
  if (h.axis_error != expired) return h;
  // The state of every 0.5 axis with its watchdog on that nobody fed since power-on: nothing
  // went wrong. Clear_Errors feeds the watchdog before it clears (every CAN frame does), and
  // the feeder keeps it fed from now on. It clears every error of the ODrive, so only this one.
  link_.send(odrive::clear_errors(node_.node_id, firmware_), "Clear_Errors");
  link_.send(odrive::request(node_.node_id, odrive::kHeartbeat, 8), "a heartbeat request");
  return await_heartbeat(settings_.heartbeat_timeout_ms,
                         "without an error after clearing WATCHDOG_TIMER_EXPIRED (the watchdog "
                         "expired before configure could feed it)",
                         &no_error);
}

std::string OdriveAxis::detect_firmware() {
  if (!settings_.odrive.detect_firmware) return "firmware " + std::string(to_string(firmware_));
  link_.send(odrive::request(node_.node_id, odrive::kGetVersion, 8), "Get_Version");
  std::optional<odrive::Version> version;
  link_.await(
      settings_.sdo_timeout_ms,
      [&](const CanFrame& f) {
        if (f.id != id_base_ + odrive::kGetVersion || f.rtr) return false;
        version = odrive::decode_version(f);
        return version.has_value();
      },
      nullptr);
  if (!version) {  // 0.5 has no Get_Version (its id 0 is the CANopen NMT message)
    firmware_ = odrive::Firmware::k05;
    return "firmware 0.5 (no answer to Get_Version)";
  }
  const std::string text =
      "firmware " + std::to_string(version->fw_major) + "." + std::to_string(version->fw_minor) +
      "." + std::to_string(version->fw_revision) + ", hardware " +
      std::to_string(version->hw_major) + "." + std::to_string(version->hw_minor) + "." +
      std::to_string(version->hw_variant);
  const auto fw = odrive::firmware_of(*version);
  if (!fw) throw DeviceError(node_name() + ": " + text + ": this driver speaks 0.5 and 0.6");
  firmware_ = *fw;
  return text;
}

void OdriveAxis::configure_watchdog() {
  const OdriveSettings& o = settings_.odrive;
  if (firmware_ != odrive::Firmware::k06 || o.watchdog_timeout_endpoint == 0) return;
  const std::uint8_t node = node_.node_id;
  const std::uint32_t timeout = float_bits(static_cast<float>(o.watchdog_timeout_s));
  link_.send(odrive::rx_sdo(node, true, o.watchdog_timeout_endpoint, timeout), "RxSdo");
  if (o.enable_watchdog_endpoint != 0) {
    link_.send(odrive::rx_sdo(node, true, o.enable_watchdog_endpoint, 1), "RxSdo");
  }
  link_.send(odrive::rx_sdo(node, false, o.watchdog_timeout_endpoint, 0), "RxSdo");
  std::optional<odrive::TxSdo> answer;
  link_.await(
      settings_.sdo_timeout_ms,
      [&](const CanFrame& f) {
        if (f.id != id_base_ + odrive::kTxSdo) return false;
        answer = odrive::decode_tx_sdo(f);
        return answer && answer->endpoint == o.watchdog_timeout_endpoint;
      },
      nullptr);
  if (!answer || answer->value != timeout) {
    throw DeviceError(node_name() + ": the axis watchdog time-out (endpoint " +
                      std::to_string(o.watchdog_timeout_endpoint) +
                      (answer ? ") reads back another value" : ") was not read back") +
                      ": check the endpoint ids against the firmware's flat_endpoints.json");
  }
}

DeviceInfo OdriveAxis::configure() {
  firmware_ = settings_.odrive.firmware;
  unsolicited_estimates_ = 0;
  controller_error_.reset();
  forget_error_status();
  notices_.clear();
  stopped_ = true;
  feed_watchdog();
  const std::string fw = detect_firmware();
  // The heartbeat comes every heartbeat period anyway; asking for it answers sooner where the
  // firmware answers remote requests for cyclic messages (0.6).
  link_.send(odrive::request(node_.node_id, odrive::kHeartbeat, 8), "a heartbeat request");
  const Heartbeat h =
      clear_expired_watchdog(await_heartbeat(settings_.heartbeat_timeout_ms, "", &any_heartbeat));
  if (h.axis_error != 0) {
    throw DeviceError(node_name() + " reports axis error " +
                      odrive::describe_axis_error(firmware_, h.axis_error) +
                      overspeed_text(h.axis_error) +
                      ": find the cause and clear it (Clear_Errors, odrivetool) first");
  }
  const std::uint8_t node = node_.node_id;
  link_.send(odrive::set_input_torque(node, 0.0f), "Set_Input_Torque");
  link_.send(odrive::set_axis_state(node, odrive::kAxisIdle), "Set_Axis_State");
  link_.send(
      odrive::set_controller_mode(node, odrive::kControlModeTorque, odrive::kInputModePassthrough),
      "Set_Controller_Mode");
  configure_watchdog();
  link_.send(odrive::request(node, odrive::kHeartbeat, 8), "a heartbeat request");
  await_heartbeat(settings_.state_timeout_ms, "showing IDLE", &idle);
  DeviceInfo info;
  info.description =
      "odrive node " + std::to_string(node) + " on " + link_.description() + " (" + fw + ")";
  info.transport_delay_samples = delay_samples(settings_, 1.0 / period_s_);
  if (settings_.odrive.position_source == PositionSource::kRequest && unsolicited_estimates_ > 0) {
    notices_.push_back(
        node_name() + ": the axis sends encoder estimates by itself (" +
        std::to_string(unsolicited_estimates_) + " while configuring: " +
        (firmware_ == odrive::Firmware::k05 ? "axis.config.can.encoder_rate_ms, 10 ms by default "
                                              "on 0.5,"
                                            : "axis.config.can.encoder_msg_rate_ms") +
        " is not 0); each tick uses only the answer to its own request, so samples stay one "
        "period apart. Set it to 0 to take them off the bus (docs/drivers/can.md)");
  }
  return info;
}

void OdriveAxis::enable() {
  answered_ = true;
  controller_error_.reset();
  forget_error_status();
  const std::uint8_t node = node_.node_id;
  feed_watchdog();  // fed until the loop's own frames take over
  stopped_ = false;
  link_.send(odrive::set_input_torque(node, 0.0f), "Set_Input_Torque");
  link_.send(odrive::set_axis_state(node, odrive::kAxisClosedLoop), "Set_Axis_State");
  const Heartbeat h =
      await_heartbeat(settings_.state_timeout_ms, "showing CLOSED_LOOP_CONTROL", &closed_loop);
  if (h.axis_error != 0) {
    throw DeviceError(node_name() + ": entering closed loop failed with axis error " +
                      odrive::describe_axis_error(firmware_, h.axis_error));
  }
}

std::array<CanFrame, 2> OdriveAxis::emergency_frames() const noexcept {
  return {odrive::set_input_torque(node_.node_id, 0.0f),
          odrive::set_axis_state(node_.node_id, odrive::kAxisIdle)};
}

bool OdriveAxis::stop_output() noexcept {
  if (stopped_) return false;  // once per enable: a fault's disable and the close after it
  stopped_ = true;             // are one stop
  for (const CanFrame& f : emergency_frames()) link_.send_quietly(f);
  return true;
}

void OdriveAxis::after_stop(const CanFault& latched, bool stopped_now) noexcept {
  if (stopped_now) {
    read_controller_error(latched);
    read_error_status(latched);
  }
  try {
    feed_watchdog();  // idle, or holding a fault: the watchdog must not add its own error
  } catch (...) {
    // No thread to be had: the watchdog may expire in IDLE, which configure clears again.
  }
}

void OdriveAxis::clear_fault() {
  controller_error_.reset();
  forget_error_status();
  link_.send(odrive::clear_errors(node_.node_id, firmware_), "Clear_Errors");
  link_.send(odrive::set_axis_state(node_.node_id, odrive::kAxisIdle), "Set_Axis_State");
  await_heartbeat(settings_.state_timeout_ms, "without an axis error", &no_error);
}

FrameMeaning OdriveAxis::on_estimates(const CanSocket::Received& rx) noexcept {
  const auto e = odrive::decode_encoder_estimates(rx.frame);
  if (!e) {
    link_.count(CanCounter::kWrongLength);
    return {};
  }
  if (settings_.odrive.position_source == PositionSource::kRequest &&
      (answered_ || rx.time_ns < request_ns_)) {
    // Not the answer to this tick's request: one the axis sent by itself (its encoder rate
    // is not 0), sampled at another instant. Taken as well it would make the samples land
    // unevenly, and the velocity the wall's damping sees jump.
    link_.count(CanCounter::kUnsolicitedEstimates);
    return {};
  }
  answered_ = true;
  position_turns_ = e->position_turns;
  velocity_turns_ = e->velocity_turns_per_s;
  last_speed_turns_ = e->velocity_turns_per_s;
  sample_time_ns_ = rx.time_ns;
  const double limit = settings_.odrive.vel_limit;
  if (limit > 0.0 && std::abs(static_cast<double>(e->velocity_turns_per_s)) > limit) {
    link_.count(CanCounter::kOverVelLimit);
  }
  FrameMeaning m;
  m.sample = true;
  return m;
}

FrameMeaning OdriveAxis::on_heartbeat(const CanFrame& f, bool active) noexcept {
  const auto h = odrive::decode_heartbeat(f);
  if (!h) {
    link_.count(CanCounter::kWrongLength);
    return {};
  }
  FrameMeaning m;
  m.heartbeat = true;
  axis_state_ = h->axis_state;
  if (h->axis_error != 0) {
    m.fault = {CanFaultKind::kAxisError, h->axis_error};
  } else if (active && h->axis_state != odrive::kAxisClosedLoop) {
    m.fault = {CanFaultKind::kAxisStateChanged, h->axis_state};
  }
  // 0.6: why it disarmed is in Get_Error; asked with the next frames (the latch's zero torque),
  // never waited for here.
  if (m.fault.kind != CanFaultKind::kNone && firmware_ == odrive::Firmware::k06 &&
      !error_requested_) {
    error_request_due_ = true;
  }
  return m;
}

FrameMeaning OdriveAxis::on_frame(const CanSocket::Received& rx, bool active) noexcept {
  const CanFrame& f = rx.frame;
  const std::uint8_t command = odrive::command_of(f.id);
  if (command == odrive::kGetEncoderEstimates) return on_estimates(rx);
  if (command == odrive::kHeartbeat) return on_heartbeat(f, active);
  if (command == odrive::kGetError && firmware_ == odrive::Firmware::k06) {
    const auto e = odrive::decode_error_status(f);
    if (!e) {
      link_.count(CanCounter::kWrongLength);
    } else if (error_requested_) {
      // Asked for, or sent every error_msg_rate_ms: either way after the heartbeat that showed
      // the fault (a node's frames keep their order). One from before it says nothing of it.
      error_status_ = *e;
    }
    return {};
  }
  link_.count(CanCounter::kUnknownIds);
  return {};
}

void OdriveAxis::sample(PositionSample& out) const noexcept {
  out.position = static_cast<double>(position_turns_) * node_.position_per_unit;
  out.velocity = static_cast<double>(velocity_turns_) * node_.position_per_unit;
  out.time_ns = sample_time_ns_;
  out.status = axis_state_;
  out.flags = kSampleHasTime | kSampleHasVelocity;
}

std::span<const CanFrame> OdriveAxis::tick_frames(double force) noexcept {
  const double torque =
      std::clamp(force * node_.torque_per_force, -node_.max_torque, node_.max_torque);
  const std::uint8_t node = node_.node_id;
  std::size_t n = 0;
  tx_[n++] = odrive::set_input_torque(node, static_cast<float>(torque));
  if (error_request_due_) {
    error_request_due_ = false;
    error_requested_ = true;
    tx_[n++] = odrive::request(node, odrive::kGetError, 8);
  }
  if (settings_.odrive.position_source != PositionSource::kRequest) return {tx_.data(), n};
  request_ns_ = base::monotonic_ns();  // before it goes out: no answer can precede it
  answered_ = false;
  tx_[n++] = odrive::request(node, odrive::kGetEncoderEstimates, 8);
  return {tx_.data(), n};
}

}  // namespace hapticd::drivers::can
