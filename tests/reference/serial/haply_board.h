// A Haply board driving a 2DIY-class pantograph (pantograph_plant.h), as its firmware behaves on
// the wire. Follows the firmware's published source, HaplyHaptics/Haply-Arduino-Firmware-Versions
// at edcf50fe (the commit that last touched these files; the repository's head is 6f75c272):
// Haply_M0_Firmware_V0_3/Haply_M0_Firmware_V0_3.ino and .h (the Haply M0 board, two actuator
// ports: the default) and Haply_M3_Firmware_V1_5/Haply_M3_Firmware_V1_5.ino and .h (the M3 board,
// four ports); and the host's side from HaplyHaptics/Haply-API-cpp at c336a06 (src/Haply/Board.cpp,
// Device.cpp, example/main.cpp).
//
// The wire, as the firmware parses it: a byte stream with no framing and no checksum. Each loop
// (every 50 us) takes one command byte if any is there:
//   0 reset:  [0, address]: every actuator, encoder, sensor and PWM pin forgets its address. The
//             motors' PWM duty is NOT cleared: a torque the host left set stays applied, until a
//             setup (initialize_actuator's pwm_setup writes a zero duty) or a write changes it.
//   1 setup:  [1, address, motor ports bitmask, a direction byte per motor, encoder ports bitmask,
//             a direction byte per encoder, sensor count, sensor pins..., PWM pin count, PWM
//             pins..., then f32 (offset in degrees, resolution) per encoder]. The example's
//             [1,5, 3,0,0, 3,0,0, 0, 0, f32 180,f32 13824, f32 0,f32 13824] is 26 bytes. Each
//             encoder's counter is written to offset * resolution / 360 (truncated) when this
//             arrives: the angle it then reports is the offset, wherever the arm really is (the
//             user holds the 2DIY at its home pose on start-up).
//   2 write:  [2, address, a pulse byte per PWM pin set up for the address, f32 torque per motor
//             of the address, in port order], answered in the same loop by [address, f32 per
//             sensor of the address, f32 angle in degrees per encoder of the address].
//   other:    the byte is dropped; the next byte is read as a command (no resynchronisation: a
//             float's 0x00, 0x01 or 0x02 is taken for a command).
// Floats are IEEE 754 single, byte 0 least significant (FloatToBytes / BytesToFloat). Single
// bytes are read with read(), which gives -1 (0xFF in a char) when nothing is there yet; the
// floats with readBytes(), which waits up to the Stream timeout (1 s) for EACH byte and leaves
// the rest of its buffer unwritten when it times out (zeros here; stack garbage on the board).
// So a short message takes the next message's bytes; a write for an address with no motor reads
// no torque bytes and its floats' bytes are parsed as commands (0.0f is four reset commands).
// Before any setup a write is answered with [address] alone (no encoder has its address); a
// write for address 0 before any setup makes the firmware dereference a null Encoder: a
// HardFault, the board hangs (hung()) with its PWM duty still applied. There is no watchdog.
//
// Motors: create_torque: |torque| clipped to MAX_TORQUE 0.123 (N m), duty = levels * |torque| /
// 0.123 truncated (1023 levels on the M0, 4095 on the M3), the direction pin HIGH for torque <= 0
// with direction byte 0 (LOW with 1). Choice (the source cannot say what a pin level turns): the
// direction pin LOW turns the shaft towards increasing angle, so with direction 0 a positive float
// drives the angle up, as Pantograph.cpp's tau = J^T f assumes. Shaft torque = +/- duty / levels
// * 0.123 N m. Encoders: the counter runs up as the angle rises with direction byte 0 (the
// firmware swaps the A and B pins for a direction above 0, so it runs down). The M0 counts half
// the encoder's edges ("encoder driver does not function as quadrature") and halves the
// resolution it was sent, so its angle steps are 720 / resolution degrees; the M3 counts them all.
// Angle = 360 * count / resolution, in degrees; the plant's joint 1 is port 1 (motor at the
// origin), joint 2 port 2; the M3's ports 3 and 4 have nothing attached.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "pantograph_plant.h"
#include "tty_io.h"

namespace hapticd::reference {

enum class HaplyFirmware { kM0V03, kM3V15 };

struct HaplyBoardOptions {
  HaplyFirmware firmware = HaplyFirmware::kM0V03;
  // The encoders' own quadrature edges per shaft turn: the resolution a host's add_encoder
  // should send (the example's 13824). A host sending another gets angles scaled by its error.
  double encoder_resolution = 13824.0;
  std::array<JointMechanics, 2> joints{};
  // Where the arms are when the board powers up (rad, Pantograph.cpp's frame): a host whose
  // encoder offsets are these angles in degrees (140 and 40 by default) sees the true pose.
  std::array<double, 2> start_angles = PantographPlant::kStartAngles;
  std::int64_t stream_timeout_ms = 1000;  // Arduino's Stream::setTimeout default
};

struct HaplyBoardCounters {
  std::uint64_t resets = 0, setups = 0, writes = 0, replies = 0;  // commands 0, 1, 2; answers
  std::uint64_t unknown_commands = 0;    // command bytes other than 0, 1, 2, each dropped
  std::uint64_t empty_reads = 0;         // read() found nothing: the firmware took 0xFF / -1
  std::uint64_t short_reads = 0;         // readBytes() timed out before its floats came
  std::uint64_t unaddressed_writes = 0;  // a write whose address owns no motor: no torque read
  std::uint64_t dropped_replies = 0;     // the tty had no room for an answer
  std::uint64_t corrupted_replies = 0;   // answers sent with a damaged header (corrupt_next)
};

class HaplyBoard {
 public:
  // Runs on `fd` (a pty master or /dev/ttyGS0), which it does not own: the test closes it, after
  // stop(), or while it runs to unplug (the board then leaves it alone).
  explicit HaplyBoard(int fd, HaplyBoardOptions options = {});
  ~HaplyBoard();  // stop()
  HaplyBoard(const HaplyBoard&) = delete;
  HaplyBoard& operator=(const HaplyBoard&) = delete;

  void start();  // the board's thread: reads, answers, steps the plant at 1 kHz
  void stop();   // joins it; the board's state stays for the test to read

  PantographPlant& plant() { return plant_; }
  const PantographPlant& plant() const { return plant_; }

  // Fault switches, any time: a hung firmware (reads and answers nothing, its motors keep their
  // duty), and the next `n` answers with their header (the address byte) damaged (bit 7
  // flipped): the only check a host can make of an answer with no checksum.
  void go_silent(bool silent) { silent_.store(silent); }
  void corrupt_next(int n) { corrupt_.store(n); }

  std::array<double, 2> motor_torque() const;    // N m on shafts 1 and 2 from the PWM now
  std::array<float, 2> received_torque() const;  // the last floats for ports 1 and 2
  std::array<float, 2> reported_angles() const;  // the last angles answered for ports 1, 2
  HaplyBoardCounters counters() const;
  bool configured() const;  // some motor or encoder holds an address (a setup, no reset since)
  bool hung() const;        // the HardFault above
  bool port_lost() const { return lost_.load(); }

 private:
  struct Port;  // one actuator port: the firmware's actuator and encoder structs
  struct Pending;

  void run();
  void advance_plant(std::int64_t now);
  void firmware_loop(std::int64_t now);
  int serial_read();
  void dispatch(std::uint8_t command, std::int64_t now);
  void forget_addresses();
  void begin_setup(std::int64_t now);
  void finish_setup(const Pending& p);
  void begin_write(std::int64_t now);
  void finish_write(const Pending& p);
  void create_torque(Port& port, float torque);
  std::int64_t edges(std::size_t port) const;
  float read_encoder(std::size_t port) const;
  void read_states();
  std::array<double, 2> shaft_torques() const;

  const int fd_;
  const HaplyBoardOptions o_;
  const int ports_, analog_pins_, pwm_levels_;
  PantographPlant plant_;
  TtyWaiter waiter_;
  std::thread thread_;
  std::atomic<bool> silent_{false}, lost_{false};
  std::atomic<int> corrupt_{0};

  mutable std::mutex m_;  // the firmware's state below, between its thread and the test
  std::vector<Port> port_;
  std::array<int, 12> sensor_host_{};
  std::array<int, 14> pwm_host_{}, pwm_pulse_{};
  std::deque<std::uint8_t> in_;
  std::vector<std::uint8_t> bytes_;
  std::unique_ptr<Pending> pending_;
  std::uint8_t address_ = 0;
  bool hung_ = false;
  std::array<float, 2> reported_{};
  HaplyBoardCounters c_;
  std::int64_t plant_ns_ = 0;
};

}  // namespace hapticd::reference
