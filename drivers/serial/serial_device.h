// The serial driver's Device (docs/drivers/serial.md): frames of the configured layouts over a
// file descriptor - a tty opened by tty_port.h, or one end of the loopback socketpair. Each
// tick read() drains what arrived, finds its frames (FrameScanner) and keeps the newest; write()
// sends one output frame. In the request exchange the device answers each output frame, so
// while output is off read() sends a zero-force frame to be answered. Status bits under the
// fault mask are a device fault; a port that errs, hangs up, will not take a frame for
// out_full_fault ticks, or sends no good frame for liveness_ms is a transport fault. Malformed
// input (bad checks, noise, overflow) is counted, never logged from the tick.
#pragma once

#include <sys/types.h>
#include <array>
#include <atomic>
#include <functional>
#include <memory>

#include "drivers/device.h"
#include "drivers/io/unique_fd.h"
#include "drivers/serial/serial_settings.h"

namespace hapticd::drivers::serial {

// How the descriptor was opened: what it reads like.
struct Port {
  io::UniqueFd fd;
  // A byte stream (a tty): a read shorter than the buffer took everything there was. false for
  // a socket of messages, read until it has none.
  bool stream = true;
  std::vector<std::string> notices;
};

class SerialDevice final : public Device {
 public:
  // Not RT-safe. `open` opens the port (called by configure, again after a close).
  SerialDevice(std::shared_ptr<const SerialSettings> settings, std::function<Port()> open,
               double sample_period_s, std::size_t joints);
  ~SerialDevice() override;

  std::string_view driver_name() const noexcept override { return "serial"; }
  std::vector<std::string> notices() const override { return notices_; }
  std::span<const base::Counter> counters() const noexcept override { return c_; }
  void emergency_stop() noexcept override;

 protected:
  DeviceInfo on_configure() override;
  void on_enable() override;
  void on_disable() noexcept override;
  void on_clear_fault() override;
  void on_close() noexcept override;
  IoStatus on_read(std::span<PositionSample> samples) noexcept override;
  IoStatus on_write(std::span<const double> forces) noexcept override;
  std::string describe(const DeviceFault& fault) const override;

 private:
  enum CounterIndex : std::size_t {
    kFrames,
    kSuperseded,
    kBadCheck,
    kSkipped,
    kOverflow,
    kSent,
    kOutFull,
    kShortWrite,
    kBacklog,
    kCounterCount
  };
  // Why a transport fault latched (DeviceFault::code): an errno, or one of these.
  static constexpr std::uint32_t kSilent = 0x10000;    // no good frame for liveness_ms
  static constexpr std::uint32_t kHangUp = 0x10001;    // the port reads end-of-file: unplugged
  static constexpr std::uint32_t kOutStuck = 0x10002;  // out_full_fault ticks without a frame out

  struct Drained {
    std::uint32_t frames = 0;
    std::uint32_t status = 0;  // every frame's status bits, OR'd
    int error = 0;             // errno, or kHangUp
  };
  // RT-safe: called every tick.
  Drained drain() noexcept;
  // RT-safe: called every tick. One frame out; false when the port failed (fault code set).
  bool send(std::span<const double> forces, bool enable) noexcept;
  void send_startup();
  void await_first_frame();
  Drained finish(const Drained& d) noexcept;
  void drop_flood() noexcept;
  static ssize_t write_all(int fd, const std::uint8_t* p, std::size_t len) noexcept;
  bool finish_tail(int fd, int& err) noexcept;
  void write_stop(int fd) noexcept;
  void publish_scan() noexcept;
  void flush_input() noexcept;

  std::shared_ptr<const SerialSettings> settings_;
  std::function<Port()> open_;
  double period_s_;
  std::size_t joints_;
  std::int64_t liveness_ns_;
  Port port_;
  std::atomic<int> emergency_fd_{-1};
  std::array<std::uint8_t, kMaxFrame> zero_frame_{};  // zero force, enable off: the stop
  std::array<std::uint8_t, 4 * kMaxFrame> rx_{};
  std::array<std::uint8_t, kMaxFrame> tx_{};
  std::array<std::uint8_t, kMaxFrame> tail_{};  // what the port owes of a frame cut short
  std::size_t tail_at_ = 0, tail_len_ = 0;
  FrameScanner scanner_;
  InputValues newest_;
  std::int64_t newest_ns_ = 0;
  std::int64_t last_frame_ns_ = 0;
  int out_streak_ = 0;
  std::uint32_t send_error_ = 0;  // why the last send failed (an errno or kOutStuck)
  std::vector<std::string> notices_;
  using K = base::CounterKind;
  std::array<base::Counter, kCounterCount> c_{{
      {"frames", K::kCount, "input frames with a good check"},
      {"superseded", K::kCount, "frames replaced by a newer one in the same tick"},
      {"bad_check", K::kAnomaly, "input frames whose check was wrong (each cost a byte)"},
      {"skipped_bytes", K::kAnomaly, "input bytes that started no frame (noise, a cut frame)"},
      {"overflow_bytes", K::kAnomaly, "input bytes dropped: more arrived than a tick holds"},
      {"frames_sent", K::kCount, "output frames the port took"},
      {"out_full", K::kAnomaly, "ticks whose frame the port would not take (its buffer full)"},
      {"short_writes", K::kAnomaly, "output frames the port took only part of (finished next)"},
      {"backlog_bytes", K::kAnomaly,
       "input bytes dropped unread: more than a tick reads (2 KB) was waiting"},
  }};
};

}  // namespace hapticd::drivers::serial
