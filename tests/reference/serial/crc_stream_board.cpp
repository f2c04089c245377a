#include "crc_stream_board.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

#include "crc.h"
#include "reference_clock.h"

namespace hapticd::reference {
namespace {

constexpr std::int64_t kStepNs = 1'000'000;  // the mechanics' longest step

void put_be(std::uint8_t* at, std::uint32_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) at[i] = static_cast<std::uint8_t>(v >> (8 * (bytes - 1 - i)));
}

std::uint16_t be16(const std::uint8_t* at) {
  return static_cast<std::uint16_t>((at[0] << 8) | at[1]);
}

}  // namespace

std::array<std::uint8_t, CrcStreamBoard::kStateFrameSize> CrcStreamBoard::state_frame(
    std::uint8_t sequence, std::int32_t count0, std::int32_t count1, std::uint8_t status) {
  std::array<std::uint8_t, kStateFrameSize> f{kSync0, kSync1, sequence};
  put_be(&f[3], static_cast<std::uint32_t>(count0) & 0xFFFFFF, 3);
  put_be(&f[6], static_cast<std::uint32_t>(count1) & 0xFFFFFF, 3);
  f[9] = status;
  put_be(&f[12], crc16_ibm3740(std::span(f).subspan(2, 10)), 2);
  return f;
}

std::array<std::uint8_t, CrcStreamBoard::kTorqueFrameSize> CrcStreamBoard::torque_frame(
    std::uint8_t flags, std::int16_t torque0_mNm, std::int16_t torque1_mNm) {
  std::array<std::uint8_t, kTorqueFrameSize> f{kSync0, kSync1, flags};
  put_be(&f[3], static_cast<std::uint16_t>(torque0_mNm), 2);
  put_be(&f[5], static_cast<std::uint16_t>(torque1_mNm), 2);
  put_be(&f[8], crc16_ibm3740(std::span(f).subspan(2, 6)), 2);
  return f;
}

CrcStreamBoard::CrcStreamBoard(int fd, CrcStreamBoardOptions options)
    : fd_(fd),
      o_(options),
      joints_{RotaryJoint(options.joints[0], options.start_angles[0]),
              RotaryJoint(options.joints[1], options.start_angles[1])},
      rate_hz_(options.rate_hz) {}

CrcStreamBoard::~CrcStreamBoard() { stop(); }

void CrcStreamBoard::start() {
  if (thread_.joinable()) return;
  waiter_.re_arm();
  {
    const std::lock_guard lock(m_);
    plant_ns_ = now_ns();
  }
  thread_ = std::thread([this] { run(); });
  run_as_device(thread_);
}

void CrcStreamBoard::stop() {
  if (!thread_.joinable()) return;
  waiter_.stop();
  thread_.join();
}

// The firmware's loop: a state frame at each period of its own clock, the torque frames as
// they come, the mechanics stepped at least every millisecond.
void CrcStreamBoard::run() {
  std::int64_t next_frame = now_ns();
  for (;;) {
    const bool listen = !silent_.load() && !lost_.load();
    const auto w = waiter_.wait(fd_, listen, std::min(next_frame, now_ns() + kStepNs));
    if (w.stop) return;
    const std::int64_t now = now_ns();
    const std::lock_guard lock(m_);
    advance(now);
    if (w.lost) lost_.store(true);
    if (listen) peer_absent_ = w.peer_absent;
    if (listen && w.input && !read_available(fd_, in_)) lost_.store(true);
    parse(now);
    if (now >= next_frame) {
      const auto period = static_cast<std::int64_t>(1e9 / std::max(1.0, rate_hz_.load()));
      // A late wake-up sends one frame, not a burst: the firmware's timer just fired late.
      next_frame += period;
      if (next_frame <= now) {
        const std::int64_t missed = (now - next_frame) / period + 1;
        c_.periods_missed += static_cast<std::uint64_t>(missed);
        next_frame += missed * period;
      }
      if (!silent_.load()) send(now);
    }
  }
}

bool CrcStreamBoard::live(std::int64_t t) const {
  return enable_ && !fault_.load() && t - last_valid_ns_ < o_.watchdog_ms * 1'000'000;
}

void CrcStreamBoard::advance(std::int64_t now) {
  while (plant_ns_ < now) {
    const std::int64_t dt = std::min(now - plant_ns_, kStepNs);
    const bool on = live(plant_ns_);
    if (was_live_ && !on && enable_ && !fault_.load()) ++c_.watchdog_trips;
    was_live_ = on;
    for (std::size_t i = 0; i < 2; ++i) {
      joints_[i].step(static_cast<double>(dt) * 1e-9, on ? torque_mNm_[i] / 1000.0 : 0.0);
    }
    plant_ns_ += dt;
  }
}

// The receiver: hunt for A5 5A, take ten bytes, check the CRC.
void CrcStreamBoard::parse(std::int64_t now) {
  for (;;) {
    std::size_t skip = 0;
    while (skip < in_.size() &&
           !(in_[skip] == kSync0 && (skip + 1 == in_.size() || in_[skip + 1] == kSync1))) {
      ++skip;
    }
    c_.bytes_skipped += skip;
    in_.erase(in_.begin(), in_.begin() + static_cast<std::ptrdiff_t>(skip));
    if (in_.size() < kTorqueFrameSize) return;
    const std::uint8_t* f = in_.data();
    if (crc16_ibm3740(std::span(f + 2, 6)) != be16(f + 8)) {
      ++c_.bad_crc;
      in_.erase(in_.begin());
      continue;
    }
    enable_ = (f[2] & 1) != 0;
    torque_mNm_ = {static_cast<std::int16_t>(be16(f + 3)), static_cast<std::int16_t>(be16(f + 5))};
    last_valid_ns_ = now;
    ++c_.valid_frames;
    in_.erase(in_.begin(), in_.begin() + kTorqueFrameSize);
  }
}

std::int32_t CrcStreamBoard::count_of(std::size_t joint) const {
  const double turns = joints_[joint].angle() / (2 * std::numbers::pi);
  const auto count = static_cast<std::int64_t>(std::floor(turns * kCountsPerTurn));
  // The 24-bit accumulator wraps: sign-extend its low 24 bits.
  const auto low = static_cast<std::uint32_t>(count) & 0xFFFFFF;
  return static_cast<std::int32_t>(low << 8) >> 8;
}

void CrcStreamBoard::send(std::int64_t now) {
  if (peer_absent_ || lost_.load()) {
    ++c_.frames_unsent;
    return;
  }
  const auto status = static_cast<std::uint8_t>((live(now) ? 1 : 0) | (fault_.load() ? 2 : 0));
  auto f = state_frame(sequence_, count_of(0), count_of(1), status);
  if (corrupt_.load() > 0) {
    corrupt_.fetch_sub(1);
    f[4] ^= 0x10;
    ++c_.corrupted_frames;
  }
  if (!write_frame(fd_, f)) {
    ++c_.frames_unsent;
    return;
  }
  ++sequence_;
  ++c_.frames_sent;
}

std::array<double, 2> CrcStreamBoard::motor_torque() const {
  return {joints_[0].motor(), joints_[1].motor()};
}

std::array<double, 2> CrcStreamBoard::commanded_torque() const {
  const std::lock_guard lock(m_);
  return {torque_mNm_[0] / 1000.0, torque_mNm_[1] / 1000.0};
}

bool CrcStreamBoard::amplifier_enabled() const {
  const std::lock_guard lock(m_);
  return live(now_ns());
}

std::array<std::int32_t, 2> CrcStreamBoard::counts() const {
  const std::lock_guard lock(m_);
  return {count_of(0), count_of(1)};
}

CrcStreamBoardCounters CrcStreamBoard::counters() const {
  const std::lock_guard lock(m_);
  return c_;
}

}  // namespace hapticd::reference
