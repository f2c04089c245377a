// The seam at several joints (drivers/device.h): one sample and one force per joint, and the
// base's refusals an amplifier must never see past - a non-finite force on any joint, a span
// for another number of joints - each ending with zero on every joint and the cause named.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "drivers/device.h"

namespace hapticd {
namespace {

class ThreeJoints final : public Device {
 public:
  explicit ThreeJoints(std::size_t joints = 3) : joints_(joints) {}
  std::string_view driver_name() const noexcept override { return "three"; }
  std::vector<std::array<double, 3>> writes;  // every on_write, zero-padded
  bool closed = false;

 protected:
  DeviceInfo on_configure() override {
    DeviceInfo info{"three joints", 0, 0};
    info.joints = joints_;
    return info;
  }
  void on_enable() override {}
  void on_disable() noexcept override {}
  void on_close() noexcept override { closed = true; }
  IoStatus on_read(std::span<PositionSample> samples) noexcept override {
    for (std::size_t j = 0; j < samples.size(); ++j) samples[j].position = 0.1 * double(j + 1);
    return IoStatus::kOk;
  }
  IoStatus on_write(std::span<const double> forces) noexcept override {
    std::array<double, 3> w{};
    for (std::size_t j = 0; j < forces.size(); ++j) w[j] = forces[j];
    writes.push_back(w);
    return IoStatus::kOk;
  }
  std::string describe(const DeviceFault&) const override { return "three: driver fault"; }

 private:
  std::size_t joints_;
};

TEST(JointSeam, EachJointReadsItsSampleAndKeepsItsCommand) {
  ThreeJoints d;
  d.configure();
  d.enable();
  std::array<PositionSample, 3> s{};
  EXPECT_EQ(d.read(s), IoStatus::kOk);
  EXPECT_DOUBLE_EQ(s[2].position, 0.3);
  const std::array<double, 3> f{1.0, -2.0, 3.0};
  EXPECT_EQ(d.write(f), IoStatus::kOk);
  ASSERT_EQ(d.writes.size(), 1u);
  EXPECT_EQ(d.writes.back(), f);
  EXPECT_EQ(d.last_command(1), -2.0);
  EXPECT_EQ(d.last_command(2), 3.0);
  d.disable();
  EXPECT_EQ(d.last_command(2), 0.0);
}

TEST(JointSeam, ANonFiniteForceOnAnyJointZeroesEveryJoint) {
  ThreeJoints d;
  d.configure();
  d.enable();
  ASSERT_EQ(d.write(std::array<double, 3>{1.0, 2.0, 3.0}), IoStatus::kOk);
  const std::array<double, 3> bad{1.0, 2.0, std::numeric_limits<double>::quiet_NaN()};
  EXPECT_EQ(d.write(bad), IoStatus::kTransportFault);
  EXPECT_EQ(d.state(), DeviceState::kFaulted);
  EXPECT_EQ(d.writes.back(), (std::array<double, 3>{0.0, 0.0, 0.0}));
  for (std::size_t j = 0; j < 3; ++j) EXPECT_EQ(d.last_command(j), 0.0);
  EXPECT_NE(d.describe_fault().find("non-finite"), std::string::npos) << d.describe_fault();
  // Latched: a finite command now passes nothing but zero.
  EXPECT_EQ(d.write(std::array<double, 3>{5.0, 5.0, 5.0}), IoStatus::kTransportFault);
  EXPECT_EQ(d.writes.back(), (std::array<double, 3>{0.0, 0.0, 0.0}));
}

TEST(JointSeam, ASpanForAnotherJointCountIsRefusedAndZeroesEveryJoint) {
  ThreeJoints d;
  d.configure();
  d.enable();
  EXPECT_EQ(d.write(1.0), IoStatus::kTransportFault);  // one force for three joints
  EXPECT_EQ(d.state(), DeviceState::kFaulted);
  ASSERT_FALSE(d.writes.empty());
  EXPECT_EQ(d.writes.back(), (std::array<double, 3>{0.0, 0.0, 0.0}));
  EXPECT_NE(d.describe_fault().find("3 the device has"), std::string::npos) << d.describe_fault();

  ThreeJoints r;
  r.configure();
  PositionSample one;
  EXPECT_EQ(r.read(one), IoStatus::kTransportFault);  // one sample for three joints
  EXPECT_EQ(r.state(), DeviceState::kFaulted);
}

TEST(JointSeam, ADeviceDeclaringNoJointsOrTooManyIsNotConfigured) {
  for (const std::size_t n : {std::size_t{0}, base::kMaxJoints + 1}) {
    ThreeJoints d(n);
    try {
      d.configure();
      FAIL() << n << " joints were configured";
    } catch (const DeviceError& e) {
      EXPECT_NE(std::string(e.what()).find(std::to_string(n) + " joints"), std::string::npos)
          << e.what();
    }
    EXPECT_EQ(d.state(), DeviceState::kUnconfigured);
    EXPECT_TRUE(d.closed);  // whatever configure opened is closed again
  }
}

}  // namespace
}  // namespace hapticd
