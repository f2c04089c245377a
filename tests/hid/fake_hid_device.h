// A scripted HID device on the far end of the loopback socketpair, for tests that need a
// device to misbehave in ways the simulated firmware never does: it answers descriptor and
// feature requests from a script, records everything the driver sends, and lets the test send
// whatever input it likes. Its thread answers requests while the driver waits for them.
#pragma once

#include <sys/socket.h>

#include <atomic>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "drivers/hid/hid_device.h"
#include "drivers/hid/hid_framing.h"
#include "drivers/hid/socket_transport.h"
#include "drivers/io/unique_fd.h"

namespace hapticd::drivers::hid::testing {

class FakeHidDevice {
 public:
  using Bytes = std::vector<std::uint8_t>;
  struct Message {
    FrameType type;
    Bytes payload;
  };

  explicit FakeHidDevice(Bytes descriptor) : descriptor_(std::move(descriptor)) {
    auto [a, b] = io::seqpacket_pair();
    host_ = std::move(a);
    fd_ = std::move(b);
    thread_ = std::thread([this] { run(); });
  }
  ~FakeHidDevice() {
    stop_.store(true);
    thread_.join();
  }

  // The driver's end, once (HidDevice opens it at configure).
  std::function<std::unique_ptr<HidTransport>()> opener(
      std::chrono::milliseconds timeout = std::chrono::milliseconds(500)) {
    return [this, timeout]() -> std::unique_ptr<HidTransport> {
      return std::make_unique<SocketTransport>(std::move(host_), timeout);
    };
  }

  // Answers to feature requests: set (return an errno or 0) and get (the report, id first).
  std::function<int(const Bytes&)> on_set_feature = [](const Bytes&) { return 0; };
  std::function<Bytes(std::uint8_t id)> on_get_feature = [](std::uint8_t) { return Bytes{}; };
  // When false, nothing is read any more: the driver's writes pile up until the socket is full.
  std::atomic<bool> reading{true};

  // One input report (as hid_read returns it) or any raw message.
  void send_input(const Bytes& report) { send_raw(frame(FrameType::kInputReport, report)); }
  void send_raw(const Bytes& message) {
    ::send(fd_.get(), message.data(), message.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  }
  // The device vanishes: its end is closed.
  void unplug() {
    const std::lock_guard lock(m_);
    ::shutdown(fd_.get(), SHUT_RDWR);
  }

  std::vector<Message> received() {
    const std::lock_guard lock(m_);
    return log_;
  }
  // Output reports received so far.
  std::vector<Bytes> outputs() {
    std::vector<Bytes> out;
    for (const Message& m : received()) {
      if (m.type == FrameType::kOutputReport) out.push_back(m.payload);
    }
    return out;
  }
  // Waits until nothing more has arrived for `quiet_ms` (what the driver had queued, all
  // taken); the messages received by then.
  std::size_t wait_quiet(int quiet_ms = 50) {
    std::size_t have = 0;
    for (int quiet = 0; quiet < quiet_ms;) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      const std::size_t now = received().size();
      quiet = now == have ? quiet + 1 : 0;
      have = now;
    }
    return have;
  }
  // Waits until `n` messages have arrived (or a second has passed).
  void wait_for(std::size_t n) {
    for (int i = 0; i < 1000 && received().size() < n; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }

 private:
  void run() {
    std::vector<std::uint8_t> buf(kMaxFrame);
    while (!stop_.load()) {
      if (!reading.load()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        continue;
      }
      const ssize_t n = ::recv(fd_.get(), buf.data(), buf.size(), MSG_DONTWAIT);
      if (n <= 0) {
        std::this_thread::sleep_for(std::chrono::microseconds(200));
        continue;
      }
      const auto f = parse_frame({buf.data(), static_cast<std::size_t>(n)});
      if (!f) continue;
      {
        const std::lock_guard lock(m_);
        log_.push_back({f->type, Bytes(f->payload.begin(), f->payload.end())});
      }
      answer(*f);
    }
  }
  void answer(const FrameView& f) {
    const Bytes payload(f.payload.begin(), f.payload.end());
    if (f.type == FrameType::kGetDescriptor) {
      send_raw(reply(FrameType::kDescriptorReply, 0, descriptor_));
    } else if (f.type == FrameType::kSetFeature) {
      send_raw(reply(FrameType::kSetFeatureReply,
                     static_cast<std::uint8_t>(on_set_feature(payload)), {}));
    } else if (f.type == FrameType::kGetFeature && !payload.empty()) {
      const Bytes r = on_get_feature(payload[0]);
      send_raw(reply(FrameType::kGetFeatureReply, r.empty() ? EPIPE : 0, r));
    }
  }

  Bytes descriptor_;
  io::UniqueFd host_, fd_;
  std::mutex m_;
  std::vector<Message> log_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace hapticd::drivers::hid::testing
