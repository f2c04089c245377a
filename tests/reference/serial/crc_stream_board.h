// A two-joint board (a two-axis gimbal or joystick) that streams its state at its own rate
// whether or not the host talks, and takes torque frames, in the format docs/drivers/serial.md
// describes for a streaming device. No firmware stands behind it: it follows that format and the
// CRC by its parametrised model (crc.h: CRC-16/IBM-3740, Williams' model with Cook's catalogue
// parameters, check 0x29B1), and behaves as such boards do: its own encoder sampling, its own
// torque watchdog, resynchronisation on the sync word.
//
// Device -> host, the state frame, 14 bytes, every 1 / rate_hz (1 kHz by default):
//   0-1   A5 5A                 sync
//   2     u8 sequence           +1 per frame sent, wraps at 256 (frames not sent take none)
//   3-5   i24 big-endian        joint 0 encoder count
//   6-8   i24 big-endian        joint 1 encoder count
//   9     u8 status             bit 0: amplifier enabled (torque is applied), bit 1: fault
//   10-11 0, 0                  reserved
//   12-13 u16 big-endian        CRC-16/IBM-3740 of bytes 2..11
// Counts: a 14-bit magnetic encoder (AS5048A class), 16384 per turn, accumulated over turns into
// the 24-bit count (wrapping at 2^24): count = floor(angle * 16384 / 2 pi), angle = count * 2 pi /
// 16384 rad.
//
// Host -> device, the torque frame, 10 bytes:
//   0-1   A5 5A                 sync
//   2     u8 flags              bit 0: enable the amplifier
//   3-4   i16 big-endian        joint 0 torque, mN m
//   5-6   i16 big-endian        joint 1 torque, mN m
//   7     reserved (sent 0; not checked)
//   8-9   u16 big-endian        CRC-16/IBM-3740 of bytes 2..7
// A frame whose CRC fails is counted and dropped from its first byte only: the hunt for A5 5A
// starts again at its second byte, so a good frame that began inside a torn one is found. Bytes
// passed over hunting are counted (a failed frame's own bytes among them). The amplifier is
// enabled while the last valid frame asked for it, it is under 100 ms old (the device's own
// watchdog: a host that goes silent leaves no torque behind) and no fault is set; it applies the
// last valid frame's torques then, none otherwise. Positive torque turns the joint towards
// increasing count. Nothing is sent while nobody has the port open (a pty master's POLLHUP, as a
// USB firmware sees DTR low): those frames are counted, and take no sequence number.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#include "mechanics.h"
#include "tty_io.h"

namespace hapticd::reference {

struct CrcStreamBoardOptions {
  double rate_hz = 1000.0;  // state frames per second (set_rate_hz changes it while running)
  std::array<JointMechanics, 2> joints{};
  std::array<double, 2> start_angles{};  // rad
  std::int64_t watchdog_ms = 100;
};

struct CrcStreamBoardCounters {
  std::uint64_t frames_sent = 0;
  std::uint64_t frames_unsent = 0;  // nobody had the port open, or it had no room
  // Periods this process woke too late for (a loaded test machine, not the device): skipped,
  // with no frame and no sequence number, as one late frame is sent instead of a burst.
  std::uint64_t periods_missed = 0;
  std::uint64_t corrupted_frames = 0;
  std::uint64_t valid_frames = 0;  // torque frames received with a good CRC
  std::uint64_t bad_crc = 0;
  std::uint64_t bytes_skipped = 0;   // passed over hunting for A5 5A
  std::uint64_t watchdog_trips = 0;  // enabled torque dropped for want of a frame
};

class CrcStreamBoard {
 public:
  static constexpr std::size_t kStateFrameSize = 14, kTorqueFrameSize = 10;
  static constexpr std::uint8_t kSync0 = 0xA5, kSync1 = 0x5A;
  static constexpr int kCountsPerTurn = 16384;

  // The device's own frame writers (for the test's own checks; the driver must not need them).
  static std::array<std::uint8_t, kStateFrameSize> state_frame(std::uint8_t sequence,
                                                               std::int32_t count0,
                                                               std::int32_t count1,
                                                               std::uint8_t status);
  static std::array<std::uint8_t, kTorqueFrameSize> torque_frame(std::uint8_t flags,
                                                                 std::int16_t torque0_mNm,
                                                                 std::int16_t torque1_mNm);

  // Runs on `fd` (a pty master or /dev/ttyGS0), which it does not own.
  explicit CrcStreamBoard(int fd, CrcStreamBoardOptions options = {});
  ~CrcStreamBoard();  // stop()
  CrcStreamBoard(const CrcStreamBoard&) = delete;
  CrcStreamBoard& operator=(const CrcStreamBoard&) = delete;

  void start();
  void stop();

  RotaryJoint& joint(std::size_t i) { return joints_[i]; }
  const RotaryJoint& joint(std::size_t i) const { return joints_[i]; }

  // Fault switches, any time: a hung firmware (sends and reads nothing; the amplifier's
  // watchdog still cuts the torque), the next `n` state frames sent with bit 4 of byte 4 (joint
  // 0's count, one turn's worth) flipped after the CRC was made, and the status's fault bit
  // (the amplifier off while it is set).
  void go_silent(bool silent) { silent_.store(silent); }
  void corrupt_next(int n) { corrupt_.store(n); }
  void set_fault(bool fault) { fault_.store(fault); }
  void set_rate_hz(double hz) { rate_hz_.store(hz); }

  std::array<double, 2> motor_torque() const;      // N m applied now
  std::array<double, 2> commanded_torque() const;  // the last valid frame's, N m
  bool amplifier_enabled() const;
  std::array<std::int32_t, 2> counts() const;  // what a frame sent now would carry
  CrcStreamBoardCounters counters() const;
  bool port_lost() const { return lost_.load(); }

 private:
  void run();
  void advance(std::int64_t now);
  bool live(std::int64_t t) const;
  void parse(std::int64_t now);
  void send(std::int64_t now);
  std::int32_t count_of(std::size_t joint) const;

  const int fd_;
  const CrcStreamBoardOptions o_;
  std::array<RotaryJoint, 2> joints_;
  TtyWaiter waiter_;
  std::thread thread_;
  std::atomic<bool> silent_{false}, fault_{false}, lost_{false};
  std::atomic<int> corrupt_{0};
  std::atomic<double> rate_hz_;

  mutable std::mutex m_;  // the state below, between the device's thread and the test
  std::vector<std::uint8_t> in_;
  bool enable_ = false, was_live_ = false, peer_absent_ = false;
  std::array<std::int16_t, 2> torque_mNm_{};
  std::int64_t last_valid_ns_ = 0, plant_ns_ = 0;
  std::uint8_t sequence_ = 0;
  CrcStreamBoardCounters c_;
};

}  // namespace hapticd::reference
