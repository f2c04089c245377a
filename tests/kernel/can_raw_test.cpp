// SocketCAN in the kernel test machine: CAN_RAW over a vcan bus, classic and FD frames, with
// the receive filter and error-frame filter a CAN driver sets.
#include <gtest/gtest.h>
#include <linux/can/error.h>

#include <chrono>
#include <cstring>

#include "sysfs.h"
#include "vcan_interface.h"

namespace hapticd::kernel_test {
namespace {

using std::chrono::milliseconds;

CanRawOptions fd_options(bool fd_frames, can_err_mask_t error_mask = 0) {
  CanRawOptions options;
  options.fd_frames = fd_frames;
  options.error_mask = error_mask;
  return options;
}

can_frame classic_frame(canid_t id, std::uint8_t seed) {
  can_frame frame{};
  frame.can_id = id;
  frame.len = 8;
  for (std::uint8_t i = 0; i < 8; ++i) frame.data[i] = static_cast<std::uint8_t>(seed + i);
  return frame;
}

TEST(CanRaw, DeliversClassicFrameThroughFilterWithErrorFramesEnabled) {
  VcanInterface bus("vcan0");
  CanRawSocket sender(bus, {});
  const can_err_mask_t errors = CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_TX_TIMEOUT;
  CanRawOptions filtered = fd_options(false, errors);
  filtered.filters = {{0x181, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG}};
  CanRawSocket receiver(bus, filtered);
  EXPECT_EQ(receiver.error_mask(), errors);

  // 0x182 does not pass the filter; 0x181 after it must be the first frame received.
  sender.send(classic_frame(0x182, 0x40));
  sender.send(classic_frame(0x181, 0x10));
  const auto got = receiver.receive(milliseconds(2000));
  ASSERT_TRUE(got.has_value()) << "no frame on " << bus.name();
  EXPECT_FALSE(got->is_fd);
  EXPECT_EQ(got->frame.can_id, 0x181u);
  ASSERT_EQ(got->frame.len, 8);
  const can_frame expected = classic_frame(0x181, 0x10);
  EXPECT_EQ(std::memcmp(got->frame.data, expected.data, 8), 0);
  EXPECT_FALSE(receiver.receive(milliseconds(200)).has_value()) << "0x182 passed the filter";
}

TEST(CanRaw, DeliversCanFdFrameOnlyToFdSockets) {
  VcanInterface bus("vcan0");
  CanRawSocket sender(bus, fd_options(true));
  CanRawSocket fd_receiver(bus, fd_options(true, CAN_ERR_MASK));
  CanRawSocket classic_receiver(bus, fd_options(false));

  canfd_frame frame{};
  frame.can_id = 0x12345678u | CAN_EFF_FLAG;
  frame.len = 64;
  frame.flags = CANFD_BRS;
  for (int i = 0; i < 64; ++i) frame.data[i] = static_cast<std::uint8_t>(0xA0 ^ i);
  sender.send(frame);

  const auto got = fd_receiver.receive(milliseconds(2000));
  ASSERT_TRUE(got.has_value());
  EXPECT_TRUE(got->is_fd);
  EXPECT_EQ(got->frame.can_id, frame.can_id);
  ASSERT_EQ(got->frame.len, 64);
  EXPECT_TRUE(got->frame.flags & CANFD_BRS);
  EXPECT_EQ(std::memcmp(got->frame.data, frame.data, 64), 0);
  // A socket without CAN_RAW_FD_FRAMES never sees an FD frame.
  EXPECT_FALSE(classic_receiver.receive(milliseconds(200)).has_value());
}

TEST(CanRaw, RefusesFdFrameOnClassicOnlyBus) {
  VcanInterface bus("vcan1", /*fd_capable=*/false);
  CanRawSocket sender(bus, fd_options(true));
  canfd_frame frame{};
  frame.can_id = 0x100;
  frame.len = 12;
  EXPECT_THROW(sender.send(frame), KernelFacilityError);  // EINVAL: the MTU is CAN_MTU
  sender.send(classic_frame(0x100, 0));                   // classic frames still go
}

}  // namespace
}  // namespace hapticd::kernel_test
