// The reference Falcon (raw_usb_ftdi.h) alone in the kernel test machine, before hapticd
// meets it: the test is the host, on libusb, taking libnifalcon's steps (f7c727aa:
// FalconCommLibUSB.cpp setFirmwareMode/setNormalMode/readBlocking, FalconFirmware.cpp
// loadFirmware with findfalcons' retries, FalconFirmwareNovintSDK.cpp runIOLoop's packets).
#include <gtest/gtest.h>
#include <libusb-1.0/libusb.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "raw_usb_ftdi.h"

namespace hapticd::reference::falcon {
namespace {

using Bytes = std::vector<std::uint8_t>;
using namespace std::chrono_literals;

bool wait_for(const std::function<bool()>& done, std::chrono::milliseconds timeout = 10s) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(5ms);
  }
  return done();
}

// The host: libnifalcon's requests on a libusb handle.
class Host {
 public:
  Host() = default;
  ~Host() {
    if (h_) libusb_close(h_);
    if (ctx_) libusb_exit(ctx_);
  }
  // libusb learns of devices from udev's events, and the machine runs no udevd: the context is
  // made once the kernel has the device (sysfs), so its first scan finds it.
  bool open() {
    if (!wait_for([] { return listed_in_sysfs(); })) return false;
    return wait_for([&] {
      if (libusb_init(&ctx_) != 0) return false;
      h_ = libusb_open_device_with_vid_pid(ctx_, 0x0403, 0xCB48);
      if (h_ == nullptr) libusb_exit(std::exchange(ctx_, nullptr));  // scan again
      return h_ != nullptr;
    });
  }
  bool claim() {
    libusb_set_auto_detach_kernel_driver(h_, 1);
    return libusb_claim_interface(h_, 0) == 0;
  }
  libusb_device_handle* handle() { return h_; }
  int vendor(std::uint8_t request, std::uint16_t value) {
    return libusb_control_transfer(h_, 0x40, request, value, 0, nullptr, 0, 1000);
  }
  int write(const Bytes& b) {
    int n = 0;
    auto* data = const_cast<std::uint8_t*>(b.data());
    return libusb_bulk_transfer(h_, 0x02, data, static_cast<int>(b.size()), &n, 1000);
  }
  // One bulk IN transfer of up to `size` bytes, the two modem bytes stripped; nothing on error.
  std::optional<Bytes> read(int size, unsigned timeout_ms = 1000) {
    Bytes buf(static_cast<std::size_t>(size));
    int n = 0;
    last_error_ = libusb_bulk_transfer(h_, 0x81, buf.data(), size, &n, timeout_ms);
    if (last_error_ != 0 || n < 2) return std::nullopt;
    return Bytes(buf.begin() + 2, buf.begin() + n);
  }
  int last_error() const { return last_error_; }

  // setFirmwareMode: purges, latency 16, 9600 8N1, no flow control, RTS low, DTR low then
  // high; check 1 up to 100 times (the Linux case: 6 bytes), then DTR low, divisor 0x15, 'A'.
  bool firmware_mode() {
    for (const auto& [r, v] : std::vector<std::pair<int, int>>{{0, 1},
                                                               {0, 2},
                                                               {9, 16},
                                                               {3, 0x4138},
                                                               {4, 8},
                                                               {2, 0},
                                                               {1, 0x0200},
                                                               {1, 0x0100},
                                                               {1, 0x0101}}) {
      if (vendor(static_cast<std::uint8_t>(r), static_cast<std::uint16_t>(v)) != 0) return false;
    }
    int i = 0;
    for (; i < 100; ++i) {
      if (write({0x0A, 0x43, 0x0D}) != 0) return false;
      const auto got = read(512);
      if (!got) return false;
      if (*got == Bytes{0x0A, 0x44, 0x2C, 0x0D}) break;
    }
    if (i == 100) return false;
    if (vendor(1, 0x0100) != 0 || vendor(3, 0x15) != 0 || write({0x41}) != 0) return false;
    const auto a = read(3);
    return a && *a == Bytes{0x41};
  }
  // loadFirmware: 62-byte chunks, each read back until all of it came, compared byte for byte;
  // then setNormalMode (latency 1, divisor 2, both purges).
  bool load(const Bytes& image) {
    if (!firmware_mode()) return false;
    for (std::size_t at = 0; at < image.size(); at += 62) {
      const std::size_t n = std::min<std::size_t>(62, image.size() - at);
      const Bytes chunk(image.begin() + static_cast<std::ptrdiff_t>(at),
                        image.begin() + static_cast<std::ptrdiff_t>(at + n));
      if (write(chunk) != 0) return false;
      Bytes echo;
      while (echo.size() < n) {
        const auto got = read(static_cast<int>(n) + 2);
        if (!got) return false;
        echo.insert(echo.end(), got->begin(), got->end());
      }
      if (echo != chunk) return false;
    }
    return vendor(9, 1) == 0 && vendor(3, 2) == 0 && vendor(0, 1) == 0 && vendor(0, 2) == 0;
  }
  // findfalcons: up to ten tries. Returns the tries taken, 0 if none succeeded.
  int load_with_retries(const Bytes& image) {
    for (int i = 1; i <= 10; ++i) {
      if (load(image)) return i;
    }
    return 0;
  }
  // One runIOLoop turn: a command out, then reads (one packet each) until a state packet.
  std::optional<Bytes> exchange(const std::array<std::int16_t, 3>& counts, std::uint8_t flags) {
    if (write(command(counts, flags)) != 0) return std::nullopt;
    const auto end = std::chrono::steady_clock::now() + 500ms;
    while (std::chrono::steady_clock::now() < end) {
      const auto got = read(64, 100);
      if (!got) continue;
      rx_.insert(rx_.end(), got->begin(), got->end());
      if (rx_.size() >= 16) {
        Bytes p(rx_.begin(), rx_.begin() + 16);
        rx_.erase(rx_.begin(), rx_.begin() + 16);
        return p;
      }
    }
    return std::nullopt;
  }
  // formatInput: '<', the three values' nibbles low first, flags, 0, '>', each nibble + 'A'.
  static Bytes command(const std::array<std::int16_t, 3>& counts, std::uint8_t flags) {
    Bytes p(16, 0x41);
    p[0] = '<';
    p[15] = '>';
    for (int i = 0; i < 3; ++i) {
      const auto v = static_cast<std::uint16_t>(counts[i]);
      for (int n = 0; n < 4; ++n)
        p[1 + 4 * i + n] = static_cast<std::uint8_t>(0x41 + ((v >> 4 * n) & 0xF));
    }
    p[13] = static_cast<std::uint8_t>(0x41 + flags);
    return p;
  }
  // formatOutput: the three encoder counts and byte 13.
  static std::array<int, 4> state(const Bytes& p) {
    std::array<int, 4> out{};
    for (int i = 0; i < 3; ++i) {
      std::uint16_t v = 0;
      for (int n = 0; n < 4; ++n)
        v |= static_cast<std::uint16_t>(((p[1 + 4 * i + n] - 0x41) & 0xF) << 4 * n);
      out[i] = static_cast<std::int16_t>(v);
    }
    out[3] = p[13] - 0x41;
    return out;
  }

 private:
  libusb_context* ctx_ = nullptr;
  libusb_device_handle* h_ = nullptr;
  Bytes rx_;
  int last_error_ = 0;
};

Bytes image(std::size_t n) {
  Bytes b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<std::uint8_t>((i * 131 + 17) >> 1);
  return b;
}

TEST(FalconDevice, EnumeratesAsTheFalconWithTheFtdiEndpoints) {
  RawUsbFtdi device;
  Host host;
  ASSERT_TRUE(host.open()) << device.error();
  libusb_device_descriptor d{};
  ASSERT_EQ(libusb_get_device_descriptor(libusb_get_device(host.handle()), &d), 0);
  EXPECT_EQ(d.idVendor, 0x0403);
  EXPECT_EQ(d.idProduct, 0xCB48);
  EXPECT_EQ(d.bcdDevice, 0x0600);
  EXPECT_EQ(d.bDeviceClass, 0);
  libusb_config_descriptor* c = nullptr;
  ASSERT_EQ(libusb_get_active_config_descriptor(libusb_get_device(host.handle()), &c), 0);
  const auto& alt = c->interface[0].altsetting[0];
  EXPECT_EQ(alt.bInterfaceClass, 0xFF);
  ASSERT_EQ(alt.bNumEndpoints, 2);
  EXPECT_EQ(alt.endpoint[0].bEndpointAddress, 0x81);
  EXPECT_EQ(alt.endpoint[1].bEndpointAddress, 0x02);
  EXPECT_EQ(alt.endpoint[0].bmAttributes & 3, LIBUSB_TRANSFER_TYPE_BULK);
  EXPECT_EQ(alt.endpoint[0].wMaxPacketSize, 64);
  libusb_free_config_descriptor(c);
  ASSERT_TRUE(host.claim());
  // The bootloader sends nothing unasked; the running firmware's chip sends the modem status
  // alone when there is nothing (the latency timer).
  EXPECT_FALSE(host.read(64, 200).has_value());
  ASSERT_EQ(host.load_with_retries(image(6000)), 1);
  const auto idle = host.read(64);
  ASSERT_TRUE(idle.has_value()) << host.last_error();
  EXPECT_TRUE(idle->empty());
  EXPECT_EQ(device.error(), "");
}

TEST(FalconDevice, LoadsAnImageExchangesPacketsAndMovesUnderForce) {
  RawUsbFtdi device;
  Host host;
  ASSERT_TRUE(host.open() && host.claim()) << device.error();
  ASSERT_EQ(host.load_with_retries(image(7324)), 1) << device.error();
  EXPECT_EQ(device.with_firmware([](FalconFirmware& f) { return f.stage(); }), Stage::kRunning);
  const auto first = host.exchange({0, 0, 0}, 0x02);
  ASSERT_TRUE(first.has_value());
  const auto s0 = Host::state(*first);
  EXPECT_EQ(s0[0], 0);
  EXPECT_EQ(s0[3] & 0x70, 0) << "homed at power-on";
  EXPECT_EQ(device.with_firmware([](FalconFirmware& f) { return f.leds(); }), 0x02);
  // A force commanded as the host would (tau = J^T F, counts = -10000 tau): the device applies
  // it within 1 %, and in homing mode the grip pushed out homes every arm.
  const Vec3 want{0, 0, 2.0};
  std::array<std::int16_t, 3> counts{};
  device.with_firmware([&](FalconFirmware& f) {
    const auto j = jacobian(f.mechanism().position());
    for (int i = 0; i < 3; ++i) {
      const double tau = (*j)[0][i] * want[0] + (*j)[1][i] * want[1] + (*j)[2][i] * want[2];
      counts[i] = static_cast<std::int16_t>(std::lround(-tau * kCountsPerNewtonMetre));
    }
    return 0;
  });
  ASSERT_TRUE(host.exchange(counts, 0x01).has_value());
  const Vec3 got =
      device.with_firmware([](FalconFirmware& f) { return f.mechanism().motor_force(); });
  std::cout << "commanded (0, 0, 2) N as counts " << counts[0] << " " << counts[1] << " "
            << counts[2] << "; applied (" << got[0] << ", " << got[1] << ", " << got[2] << ") N\n";
  EXPECT_NEAR(got[2], want[2], 0.01 * want[2]);
  EXPECT_NEAR(std::hypot(got[0], got[1]), 0, 0.01 * want[2]);
  std::array<int, 4> s{};
  for (int i = 0; i < 300; ++i) {
    const auto p = host.exchange(counts, 0x01);
    ASSERT_TRUE(p.has_value()) << "packet " << i;
    s = Host::state(*p);
    std::this_thread::sleep_for(1ms);
  }
  std::cout << "after 300 packets: encoders " << s[0] << " " << s[1] << " " << s[2]
            << ", byte 13 0x" << std::hex << s[3] << std::dec << "\n";
  EXPECT_GT(std::abs(s[0]), 100) << "the encoders did not move";
  EXPECT_EQ((s[3] >> 4) & 7, 7) << "not homed";
  EXPECT_EQ(device.with_firmware([](FalconFirmware& f) { return f.malformed(); }), 0u);
  // A purge discards what the chip held: the answer to an unread command never arrives.
  ASSERT_EQ(host.write(Host::command({0, 0, 0}, 0)), 0);
  ASSERT_TRUE(wait_for(
      [&] { return device.with_firmware([](FalconFirmware& f) { return f.packets(); }) >= 302; }));
  ASSERT_EQ(host.vendor(0, 1), 0);
  EXPECT_GE(device.withdrawn(), 1u) << "nothing was queued to take back";
  for (int i = 0; i < 5; ++i) {
    const auto r = host.read(64, 100);
    if (r) {
      EXPECT_TRUE(r->empty()) << "stale data after the purge";
    }
  }
  EXPECT_EQ(device.error(), "");
}

TEST(FalconDevice, BootloaderFailingTheFirstTryLoadsOnTheSecond) {
  FirmwareOptions o;
  o.fail_first_try = true;
  RawUsbFtdi device(o);
  Host host;
  ASSERT_TRUE(host.open() && host.claim());
  EXPECT_EQ(host.load_with_retries(image(8492)), 2) << device.error();
  EXPECT_EQ(device.with_firmware([](FalconFirmware& f) { return f.resets(); }), 2u);
  EXPECT_TRUE(host.exchange({0, 0, 0}, 0).has_value());
}

TEST(FalconDevice, HungAndSilentDevicesSendOnlyStatus) {
  FirmwareOptions o;
  o.silent_firmware = true;
  RawUsbFtdi device(o);
  Host host;
  ASSERT_TRUE(host.open() && host.claim());
  ASSERT_EQ(host.load_with_retries(image(4096)), 1);
  EXPECT_FALSE(host.exchange({0, 0, 0}, 0).has_value());
  EXPECT_GE(device.status_packets(), 5u);
  device.with_firmware([](FalconFirmware& f) { return f.hang(), 0; });
  EXPECT_FALSE(host.exchange({0, 0, 0}, 0).has_value());
}

// A host loading again over a running firmware (the DTR pulse resets the microcontroller):
// what the running chip had queued must not spoil the handshake.
TEST(FalconDevice, LoadsAgainOverARunningFirmware) {
  RawUsbFtdi device;
  Host host;
  ASSERT_TRUE(host.open() && host.claim());
  ASSERT_EQ(host.load_with_retries(image(4500)), 1);
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(host.exchange({100, 100, 100}, 0).has_value());
  EXPECT_EQ(host.load_with_retries(image(7324)), 1) << device.error();
  EXPECT_EQ(device.with_firmware([](FalconFirmware& f) { return f.image_size(); }), 7324u);
  EXPECT_TRUE(host.exchange({0, 0, 0}, 0).has_value());
}

TEST(FalconDevice, UnplugIsSeenByTheHost) {
  auto device = std::make_unique<RawUsbFtdi>();
  Host host;
  ASSERT_TRUE(host.open() && host.claim());
  ASSERT_EQ(host.load_with_retries(image(5000)), 1);
  ASSERT_TRUE(host.exchange({0, 0, 0}, 0).has_value());
  device->unplug();
  EXPECT_TRUE(wait_for(
      [&] {
        host.read(64, 100);
        return host.last_error() == LIBUSB_ERROR_NO_DEVICE ||
               host.last_error() == LIBUSB_ERROR_IO || host.last_error() == LIBUSB_ERROR_PIPE;
      },
      5s))
      << host.last_error();
}

}  // namespace
}  // namespace hapticd::reference::falcon
