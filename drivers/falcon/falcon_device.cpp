#include "drivers/falcon/falcon_device.h"

#include <algorithm>
#include <cmath>
#include <thread>

#include "base/clock.h"
#include "base/errno_text.h"

namespace hapticd::drivers::falcon {
namespace {

constexpr std::uint8_t kAllHomed = 0x7;

std::string homed_text(std::uint8_t bits) {
  std::string s;
  for (int j = 0; j < 3; ++j) {
    if ((bits >> j & 1) != 0) continue;
    s += (s.empty() ? "" : ", ") + std::to_string(j);
  }
  return s.empty() ? "none" : s;
}

}  // namespace

FalconDevice::FalconDevice(std::shared_ptr<const FalconSettings> settings,
                           std::function<std::unique_ptr<FalconTransport>()> open,
                           double sample_period_s, const LoaderTiming& timing)
    : settings_(std::move(settings)),
      open_(std::move(open)),
      period_s_(sample_period_s),
      timing_(timing),
      liveness_ns_(static_cast<std::int64_t>(settings_->liveness_ms * 1e6)) {}

FalconDevice::~FalconDevice() { close(); }

DeviceInfo FalconDevice::on_configure() {
  const std::vector<unsigned char> image = read_firmware_image(settings_->firmware);
  transport_ = open_();
  emergency_.store(transport_.get());  // a crash while loading or homing stops the device too
  notices_.clear();
  stream_.clear();
  try {
    if (firmware_running(*transport_, timing_)) {
      notices_.push_back("falcon: Novint's firmware was running already: not loaded again");
    } else {
      const LoadResult r = load_firmware(*transport_, image, settings_->load_tries, timing_);
      if (!r.loaded) {
        throw DeviceError("falcon: the firmware did not load in " +
                          std::to_string(settings_->load_tries) + " tries: " + falcon::describe(r));
      }
      if (r.tries.size() > 1) notices_.push_back("falcon: firmware load: " + falcon::describe(r));
    }
    home();
    transport_->start();  // the exchange's own threads, where the transport has them
  } catch (...) {
    emergency_.store(nullptr);
    transport_.reset();
    throw;
  }
  asked_ns_ = 0;
  DeviceInfo info;
  info.description = transport_->describe();
  info.transport_delay_samples = declared_delay_samples(period_s_);
  info.joints = 3;
  return info;
}

// Packets with the homing bit, LED red, until the firmware says every encoder is homed.
void FalconDevice::home() {
  const auto timeout_ms = static_cast<std::int64_t>(settings_->homing_timeout_s * 1e3);
  const std::int64_t deadline = base::monotonic_ms() + timeout_ms;
  std::uint8_t homed = 0;
  std::vector<unsigned char> in(4 * kUsbPacketBytes);
  while (base::monotonic_ms() < deadline) {
    Command c;
    c.homing = true;
    c.leds = kLedRed;
    std::string error;
    if (!transport_->write(encode_command(c), timing_.answer_ms, error)) {
      throw DeviceError("falcon: while homing: " + error);
    }
    const int n = transport_->read(in, timing_.answer_ms, error);
    if (n < 0) throw DeviceError("falcon: while homing: " + error);
    stream_.feed_transfer({in.data(), static_cast<std::size_t>(n)});
    Packet p;
    State s;
    while (stream_.next(p)) {
      if (decode_state(p, s) == PacketError::kNone) homed = s.homed;
    }
    if (homed == kAllHomed) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  throw DeviceError("falcon: not homed within " + std::to_string(timeout_ms / 1000) +
                    " s (encoders not homed: " + homed_text(homed) +
                    "): with the LED red, pull the grip all the way out, then push it in");
}

void FalconDevice::on_enable() {
  // What arrived since homing answered packets long gone: the first tick reads only answers
  // to its own packets (a sample timed seconds ago is stale to the loop, rightly).
  if (transport_->receive(stream_) == TransportIo::kError) {
    throw DeviceError("falcon: enabling: " + base::errno_text(transport_->error()));
  }
  stream_.clear();
  asked_ns_ = 0;
  if (!send({0, 0, 0}, kLedGreen)) {
    throw DeviceError("falcon: enabling: " + base::errno_text(transport_->error()));
  }
}

void FalconDevice::send_zero(std::uint8_t leds) noexcept {
  if (transport_) send({0, 0, 0}, leds);
}

void FalconDevice::on_disable() noexcept {
  send_zero(state() == DeviceState::kFaulted ? kLedRed : kLedBlue);
}

void FalconDevice::on_clear_fault() {
  send_zero(kLedBlue);
  if (newest_.homed != kAllHomed) {
    throw DeviceError("falcon: homing was lost (encoders not homed: " + homed_text(newest_.homed) +
                      "): close and configure again to home it");
  }
}

void FalconDevice::on_close() noexcept {
  send_zero(0);
  emergency_.store(nullptr);
  transport_.reset();
}

void FalconDevice::emergency_stop() noexcept {
  if (FalconTransport* t = emergency_.load()) t->emergency(encode_command(Command{}));
}

bool FalconDevice::send(const std::array<std::int16_t, 3>& motor, std::uint8_t leds) noexcept {
  Command c;
  c.motor = motor;
  c.leds = leds;
  c.homing = true;  // the firmware keeps the device homed only while every packet says so
  switch (transport_->send(encode_command(c))) {
    case TransportIo::kOk:
      if (asked_ns_ == 0) asked_ns_ = base::monotonic_ns();
      c_[kSent].add();
      return true;
    case TransportIo::kEmpty:
      c_[kOutFull].add();
      return true;
    case TransportIo::kError:
      break;
  }
  set_fault_code(static_cast<std::uint32_t>(transport_->error()));
  return false;
}

int FalconDevice::drain() noexcept {
  if (transport_->receive(stream_) == TransportIo::kError) {
    set_fault_code(static_cast<std::uint32_t>(transport_->error()));
    return -1;
  }
  int good = 0;
  Packet p;
  State s;
  while (stream_.next(p)) {
    if (decode_state(p, s) != PacketError::kNone) {
      c_[kMalformed].add();
      continue;
    }
    newest_ = s;
    ++good;
  }
  publish_stream();
  return good;
}

void FalconDevice::publish_stream() noexcept {
  c_[kSkipped].set(stream_.skipped_bytes());
  c_[kOverflow].set(stream_.overflowed_bytes());
}

IoStatus FalconDevice::on_read(std::span<PositionSample> samples) noexcept {
  const int good = drain();
  if (good < 0) return IoStatus::kTransportFault;
  const std::int64_t now = base::monotonic_ns();
  if (state() != DeviceState::kActive) send_zero(kLedBlue);  // the firmware answers packets
  if (good == 0) {
    // Silence counts from the first packet sent since the last answer: the firmware speaks
    // only when spoken to, so a pause before the first tick is no silence.
    if (asked_ns_ == 0 || now - asked_ns_ <= liveness_ns_) return IoStatus::kNoNewData;
    set_fault_code(kSilent);
    return IoStatus::kTransportFault;
  }
  asked_ns_ = 0;
  c_[kPackets].add(static_cast<std::uint64_t>(good));
  c_[kSuperseded].add(static_cast<std::uint64_t>(good - 1));
  if (newest_.homed != kAllHomed) {
    homing_code_ = newest_.homed;
    set_fault_code(kHomingLost);
    return IoStatus::kDeviceFault;
  }
  // When the packet reached the host: the loop judges a jump over the time that really passed.
  const std::int64_t at = transport_->received_ns();
  for (std::size_t j = 0; j < samples.size(); ++j) {
    samples[j].position = arm_angle(newest_.encoder[j]);
    samples[j].status = static_cast<std::uint32_t>(newest_.grip | newest_.homed << 4);
    samples[j].time_ns = at;
    samples[j].flags = at > 0 ? kSampleHasTime : 0;
  }
  return IoStatus::kOk;
}

IoStatus FalconDevice::on_write(std::span<const double> forces) noexcept {
  std::array<std::int16_t, 3> motor{};
  for (std::size_t j = 0; j < motor.size(); ++j) {
    // The section bounds device.max_force within 32767 counts and the controller saturates
    // at it: the clamp only rounds the last count.
    const double counts = std::round(forces[j] * settings_->counts_per_newton_metre);
    motor[j] = static_cast<std::int16_t>(std::clamp(counts, -32767.0, 32767.0));
  }
  // A latched fault's zero (the base writes it in FAULTED) turns the LED red.
  const std::uint8_t led = state() == DeviceState::kFaulted ? kLedRed : kLedGreen;
  return send(motor, led) ? IoStatus::kOk : IoStatus::kTransportFault;
}

std::string FalconDevice::describe(const DeviceFault& fault) const {
  switch (fault.code) {
    case kSilent:
      return "falcon: no packet for " + std::to_string(static_cast<int>(settings_->liveness_ms)) +
             " ms: the device hung or its firmware stopped";
    case kHomingLost:
      return "falcon: the firmware lost its homing (encoders not homed: " +
             homed_text(static_cast<std::uint8_t>(homing_code_)) + ")";
    case ENODEV:
      return "falcon: the device is gone";
    default:
      return "falcon: " + base::errno_text(static_cast<int>(fault.code));
  }
}

}  // namespace hapticd::drivers::falcon
