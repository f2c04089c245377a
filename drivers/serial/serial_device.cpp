#include "drivers/serial/serial_device.h"

#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <thread>

#include "base/clock.h"
#include "base/errno_text.h"
#include "base/hex.h"
#include "drivers/serial/tty_port.h"

namespace hapticd::drivers::serial {
namespace {

// Bytes a tick scans at most (two reads of a tty, or as many of a socket's messages): a device
// sending more than that a period floods the port; what is left is dropped and counted, so the
// tick's work stays bounded.
constexpr std::size_t kMaxBytesPerTick = 2048;

}  // namespace

SerialDevice::SerialDevice(std::shared_ptr<const SerialSettings> settings,
                           std::function<Port()> open, double sample_period_s, std::size_t joints)
    : settings_(std::move(settings)),
      open_(std::move(open)),
      period_s_(sample_period_s),
      joints_(joints),
      liveness_ns_(std::llround(settings_->liveness_ms * 1e6)),
      scanner_(settings_->input.shape) {
  const std::array<double, base::kMaxJoints> zero{};
  encode_output(std::span(zero.data(), joints_), false, settings_->output, zero_frame_);
}

SerialDevice::~SerialDevice() { on_close(); }

DeviceInfo SerialDevice::on_configure() {
  port_ = open_();
  notices_ = port_.notices;
  if (!settings_->input.shape.check) {
    notices_.push_back(
        "device.serial.input has no check: a damaged frame reaches the loop, "
        "which faults only on a jump beyond safety.max_speed");
  }
  scanner_.clear();
  out_streak_ = 0;
  tail_len_ = 0;
  emergency_fd_.store(port_.fd.get());  // a crash while configuring stops the device too
  try {
    send_startup();
    await_first_frame();
  } catch (...) {
    emergency_fd_.store(-1);
    port_.fd.reset();
    throw;
  }
  last_frame_ns_ = base::monotonic_ns();  // the liveness bound starts at the first frame
  DeviceInfo info;
  info.description = "serial " + settings_->port;
  info.transport_delay_samples = declared_delay_samples(*settings_, period_s_);
  if (settings_->input.sequence)
    info.sequence_modulus = field::counter_modulus(*settings_->input.sequence);
  info.joints = joints_;
  return info;
}

void SerialDevice::send_startup() {
  for (const auto& frame : settings_->startup) {
    const ssize_t n = ::write(port_.fd.get(), frame.data(), frame.size());
    if (n != static_cast<ssize_t>(frame.size())) {
      throw DeviceError(
          "serial port " + settings_->port + ": a startup frame could not be sent (" +
          (n < 0 ? base::errno_text(errno)
                 : std::to_string(n) + " of " + std::to_string(frame.size()) + " bytes") +
          ")");
    }
    std::this_thread::sleep_for(
        std::chrono::duration<double, std::milli>(settings_->startup_gap_ms));
  }
}

// The device speaks before anything is enabled: its first good frame within answer_timeout_ms
// (asked for with zero-force frames in the request exchange), or configure fails saying what
// arrived instead.
void SerialDevice::await_first_frame() {
  const std::int64_t deadline =
      base::monotonic_ns() + std::llround(settings_->answer_timeout_ms * 1e6);
  const std::uint64_t frames0 = c_[kFrames].value();
  while (base::monotonic_ns() < deadline) {
    if (settings_->exchange == Exchange::kRequest && !send({}, false)) {
      throw DeviceError(describe({FaultClass::kTransport, send_error_}));
    }
    pollfd p{port_.fd.get(), POLLIN, 0};
    ::poll(&p, 1, std::max(1, static_cast<int>(period_s_ * 1e3)));
    const Drained d = drain();
    if (d.error != 0) {
      throw DeviceError(describe({FaultClass::kTransport, static_cast<std::uint32_t>(d.error)}));
    }
    if (c_[kFrames].value() == frames0) continue;
    // The first tick's read finds the answer to this one.
    if (settings_->exchange == Exchange::kRequest) (void)send({}, false);
    return;
  }
  const ScanCounts& s = scanner_.counts();
  throw DeviceError("serial port " + settings_->port + ": no good frame within " +
                    std::to_string(static_cast<int>(settings_->answer_timeout_ms)) +
                    " ms (device.serial.answer_timeout_ms): " + std::to_string(s.skipped) +
                    " bytes started no frame, " + std::to_string(s.bad_check) +
                    " frames had a wrong check; check the baud rate, the exchange (" +
                    (settings_->exchange == Exchange::kRequest
                         ? "request: the device must answer each frame"
                         : "stream: the device must send on its own") +
                    "), input.sync and input.length");
}

// Frames a streaming device sent while the gate ran are history: the loop starts on new ones,
// never fast-forwarding through them a read at a time.
void SerialDevice::flush_input() noexcept {
  if (port_.stream) {
    discard_input(port_.fd.get());
  } else {
    while (::read(port_.fd.get(), rx_.data(), rx_.size()) > 0) {
    }
  }
  scanner_.clear();
}

// After a fault: what arrived meanwhile is history, and the liveness bound starts again.
void SerialDevice::on_clear_fault() {
  flush_input();
  out_streak_ = 0;
  last_frame_ns_ = base::monotonic_ns();
}

void SerialDevice::on_enable() {
  flush_input();
  // The first tick's read finds the answer to this one.
  if (settings_->exchange == Exchange::kRequest) (void)send({}, false);
  out_streak_ = 0;
  last_frame_ns_ = base::monotonic_ns();  // the liveness bound starts now
}

// The stop frame, after whatever of an earlier frame the port still owes the device: a frame cut
// short shifts every byte after it (a device without framing takes them for commands).
void SerialDevice::write_stop(int fd) noexcept {
  int err = 0;
  if (!finish_tail(fd, err)) return;
  (void)write_all(fd, zero_frame_.data(), settings_->output.shape.length);
}

void SerialDevice::on_disable() noexcept {
  if (port_.fd) write_stop(port_.fd.get());
}

void SerialDevice::on_close() noexcept {
  emergency_fd_.store(-1);
  on_disable();
  port_.fd.reset();
}

// Async-signal-safe: write(2) on the open descriptor, nothing else.
void SerialDevice::emergency_stop() noexcept {
  const int fd = emergency_fd_.load();
  if (fd >= 0) write_stop(fd);
}

void SerialDevice::publish_scan() noexcept {
  const ScanCounts& s = scanner_.counts();
  c_[kFrames].set(s.frames);
  c_[kBadCheck].set(s.bad_check);
  c_[kSkipped].set(s.skipped);
  c_[kOverflow].set(s.overflowed);
}

SerialDevice::Drained SerialDevice::drain() noexcept {
  Drained d;
  for (std::size_t taken = 0;;) {
    if (taken >= kMaxBytesPerTick) {
      drop_flood();
      break;
    }
    const ssize_t n = ::read(port_.fd.get(), rx_.data(), rx_.size());
    if (n == 0) {  // a tty hung up, a socket's peer gone: the device is unplugged
      d.error = static_cast<int>(kHangUp);
      break;
    }
    if (n < 0) {
      if (errno != EAGAIN && errno != EINTR) d.error = errno;
      break;
    }
    scanner_.push({rx_.data(), static_cast<std::size_t>(n)});
    for (auto f = scanner_.next(); !f.empty(); f = scanner_.next()) {
      decode_input(f, settings_->input, newest_);
      d.status |= newest_.status;  // a fault bit in a superseded frame is a fault all the same
      ++d.frames;
    }
    taken += static_cast<std::size_t>(n);
    // A tty's short read took everything there was; a socket is read until it has nothing.
    if (static_cast<std::size_t>(n) < rx_.size() && port_.stream) break;
  }
  return finish(d);
}

SerialDevice::Drained SerialDevice::finish(const Drained& d) noexcept {
  if (d.frames > 1) c_[kSuperseded].add(d.frames - 1);
  publish_scan();
  return d;
}

// RT-safe. More than a tick reads (2 KB) still waiting: a flood, or a loop held up for a long
// time. Dropped unread and counted, so a tick's work stays bounded (the scan checks a candidate
// at every sync byte); a device that numbers its frames shows the drop as a sequence gap.
void SerialDevice::drop_flood() noexcept {
  int n = 0;
  if (::ioctl(port_.fd.get(), FIONREAD, &n) == 0 && n > 0) {
    c_[kBacklog].add(static_cast<std::uint64_t>(n));
    if (port_.stream) {
      discard_input(port_.fd.get());
    } else {
      while (::read(port_.fd.get(), rx_.data(), rx_.size()) > 0) {
      }
    }
  }
}

IoStatus SerialDevice::on_read(std::span<PositionSample> samples) noexcept {
  const std::int64_t now = base::monotonic_ns();
  const bool active = state() == DeviceState::kActive;
  const Drained d = drain();
  if (d.error != 0) {
    set_fault_code(static_cast<std::uint32_t>(d.error));
    return IoStatus::kTransportFault;
  }
  // Output off in the request exchange: nothing else asks the device for its position.
  if (!active && settings_->exchange == Exchange::kRequest && !send({}, false)) {
    return IoStatus::kTransportFault;
  }
  if (d.frames == 0) {
    if (now - last_frame_ns_ <= liveness_ns_) return IoStatus::kNoNewData;
    set_fault_code(kSilent);
    return IoStatus::kTransportFault;
  }
  last_frame_ns_ = now;
  for (std::size_t j = 0; j < samples.size(); ++j) {
    PositionSample& s = samples[j];
    s.position = newest_.position[j];
    s.time_ns = now;
    s.status = newest_.status;
    s.sequence = newest_.sequence;
    s.flags = static_cast<std::uint8_t>(kSampleHasTime |
                                        (settings_->input.sequence ? kSampleHasSequence : 0));
    s.samples = d.frames;
  }
  if (active && (d.status & settings_->input.fault_mask) != 0) {
    set_fault_code(d.status & settings_->input.fault_mask);
    return IoStatus::kDeviceFault;
  }
  return IoStatus::kOk;
}

// The enable switch only while ACTIVE: the zero a fault writes (the base latches FAULTED
// first) and every frame after it say off.
IoStatus SerialDevice::on_write(std::span<const double> forces) noexcept {
  return send(forces, state() == DeviceState::kActive) ? IoStatus::kOk : IoStatus::kTransportFault;
}

// RT-safe. write(2) again after a signal; what the port took, or -1 with errno.
ssize_t SerialDevice::write_all(int fd, const std::uint8_t* p, std::size_t len) noexcept {
  ssize_t n;
  do {
    n = ::write(fd, p, len);
  } while (n < 0 && errno == EINTR);
  return n;
}

// RT-safe. What the port still owes the device of a frame it took only part of; true once none
// is left, false (err set on a failure, 0 when the port is full) otherwise.
bool SerialDevice::finish_tail(int fd, int& err) noexcept {
  while (tail_len_ > 0) {
    const ssize_t n = write_all(fd, tail_.data() + tail_at_, tail_len_);
    if (n <= 0) {
      err = n < 0 && errno != EAGAIN ? errno : 0;
      return false;
    }
    tail_at_ += static_cast<std::size_t>(n);
    tail_len_ -= static_cast<std::size_t>(n);
  }
  return true;
}

// RT-safe: called every tick. One whole frame out; a frame the port takes part of is finished
// before anything else is sent. A port that takes nothing for out_full_fault ticks faults.
bool SerialDevice::send(std::span<const double> forces, bool enable) noexcept {
  const std::size_t len = settings_->output.shape.length;
  if (forces.empty()) {
    std::copy_n(zero_frame_.begin(), len, tx_.begin());
  } else {
    encode_output(forces, enable, settings_->output, tx_);
  }
  int err = 0;
  ssize_t n = 0;
  if (finish_tail(port_.fd.get(), err)) n = write_all(port_.fd.get(), tx_.data(), len);
  if (err != 0 || (n < 0 && errno != EAGAIN)) {
    send_error_ = static_cast<std::uint32_t>(err != 0 ? err : errno);
    set_fault_code(send_error_);
    return false;
  }
  if (n == static_cast<ssize_t>(len)) {
    c_[kSent].add();
    out_streak_ = 0;
    return true;
  }
  if (n > 0) {  // the rest goes first next time, whatever is sent then
    tail_at_ = 0;
    tail_len_ = len - static_cast<std::size_t>(n);
    std::copy_n(tx_.begin() + n, tail_len_, tail_.begin());
    c_[kShortWrite].add();
  } else {
    c_[kOutFull].add();
  }
  if (++out_streak_ < settings_->out_full_fault) return true;
  // A port that takes nothing may be one being unplugged whose hang-up is on its way: say so if
  // the kernel already knows (the fault path only: one poll).
  pollfd p{port_.fd.get(), 0, 0};
  send_error_ =
      ::poll(&p, 1, 0) > 0 && (p.revents & (POLLHUP | POLLERR)) != 0 ? kHangUp : kOutStuck;
  set_fault_code(send_error_);
  return false;
}

std::string SerialDevice::describe(const DeviceFault& fault) const {
  const std::string port = "serial port " + settings_->port;
  if (fault.fault_class == FaultClass::kDevice) {
    return port + ": the device reported a fault: status bits " + base::hex(fault.code) +
           " under device.serial.input.fault_mask";
  }
  switch (fault.code) {
    case kSilent:
      return port + " is silent: no good frame for " +
             std::to_string(static_cast<int>(settings_->liveness_ms)) +
             " ms (device.serial.liveness_ms): the device hung, or its frames are all damaged";
    case kHangUp:
    case EIO:
    case ENODEV:
      return port + " hung up: the device was unplugged or reset (" +
             (fault.code == kHangUp ? std::string("end of file")
                                    : base::errno_text(static_cast<int>(fault.code))) +
             ")";
    case kOutStuck:
      return port + " took no whole frame for " + std::to_string(settings_->out_full_fault) +
             " ticks in a row (device.serial.out_full_fault): the device stopped reading, or is "
             "being unplugged";
    default:
      return port + ": " + base::errno_text(static_cast<int>(fault.code));
  }
}

}  // namespace hapticd::drivers::serial
