// Malformed input of every kind, at every layer: reports too short, of unknown ids, empty, too
// long, unknown message types and random bytes reach the driver from a device; random and
// truncated descriptors reach the parser; random reports reach the simulated firmware. Each is
// counted or refused with a clean error, never a crash (the sanitizer build runs these too).
#include <gtest/gtest.h>

#include <random>

#include "alloc_counter.h"
#include "drivers/hid/descriptor_builder.h"
#include "drivers/hid/pid_protocol.h"
#include "fake_hid_device.h"
#include "hid_test_support.h"
#include "sim/peers/hid/hid_firmware.h"

namespace hapticd::drivers::hid {
namespace {

using Bytes = std::vector<std::uint8_t>;

TEST(HidMalformed, BadReportsAreCountedByKindAndTheLoopGoesOn) {
  const auto s = testing::settings_of(testing::load_example("hid-report.yaml"));
  testing::FakeHidDevice fake(report_profile_descriptor(s->report));
  HidDevice device(s, fake.opener(), 1e-3);
  device.configure();
  device.enable();
  fake.send_input({1, 2, 3});                    // our id, too short
  fake.send_input({9, 0, 0, 0, 0, 0, 0, 0, 0});  // an id the profile does not use
  fake.send_input({});                           // nothing at all
  fake.send_input(Bytes(3000, 1));               // longer than any report
  fake.send_raw({0x77, 1, 2});                   // not a message type at all
  fake.send_raw({static_cast<std::uint8_t>(FrameType::kSetFeatureReply), 0});  // a stray reply
  Bytes good(input_report_size(s->report.input));
  encode_input({.position = {0.002}, .sequence = 7, .status = 0}, s->report.input, good);
  fake.send_input(good);
  std::this_thread::sleep_for(std::chrono::milliseconds(10));
  PositionSample sample;
  ASSERT_EQ(device.read(sample), IoStatus::kOk);
  EXPECT_NEAR(sample.position, 0.002, 1e-9);
  const HidCounters c = device.hid_counts();
  EXPECT_EQ(c.too_short, 2u);  // the short one and the empty one
  EXPECT_EQ(c.unknown_id, 1u);
  EXPECT_EQ(c.too_long, 1u);
  EXPECT_EQ(c.input_reports, 1u);
}

TEST(HidMalformed, RandomInputNeverCrashesTheDriver) {
  for (const char* example : {"hid-report.yaml", "hid-pid.yaml"}) {
    const auto s = testing::settings_of(testing::load_example(example));
    const Bytes descriptor = s->profile == Profile::kReport ? report_profile_descriptor(s->report)
                                                            : pid_reference_descriptor();
    testing::FakeHidDevice fake(descriptor);
    const auto l = find_pid_layout(*parse_report_descriptor(pid_reference_descriptor()).descriptor,
                                   kGenericDesktopX);
    fake.on_get_feature = [&](std::uint8_t) {
      Bytes r = make_report(l.layout->block_load, true);
      set_slot(std::span<std::uint8_t>(r).subspan(1), l.layout->bl_block, 1);
      choose(std::span<std::uint8_t>(r).subspan(1), l.layout->bl_success);
      return r;
    };
    HidDevice device(s, fake.opener(), 1e-3);
    device.configure();
    device.enable();
    std::mt19937 rng(42);
    PositionSample sample;
    for (int i = 0; i < 3000; ++i) {
      Bytes r(rng() % 40);
      for (auto& b : r) b = static_cast<std::uint8_t>(rng() % 8 == 0 ? rng() % 8 : rng());
      fake.send_input(r);
      if (i % 16 == 0) {
        const IoStatus st = device.read(sample);
        if (st == IoStatus::kDeviceFault) break;  // a random status bit: fine, and latched
        ASSERT_NE(st, IoStatus::kTransportFault) << device.describe_fault();
      }
    }
    const HidCounters c = device.hid_counts();
    EXPECT_GT(c.too_short + c.unknown_id + c.input_reports + c.state_reports, 0u) << example;
  }
}

TEST(HidMalformed, MutatedAndTruncatedDescriptorsParseOrFailCleanly) {
  std::mt19937 rng(7);
  const Bytes reference = pid_reference_descriptor();
  int parsed = 0, refused = 0;
  for (std::size_t cut = 0; cut <= reference.size(); ++cut) {  // every truncation
    const auto p = parse_report_descriptor(std::span(reference).first(cut));
    (p.descriptor ? parsed : refused)++;
    if (!p.descriptor) {
      EXPECT_FALSE(p.error.empty());
    }
  }
  for (int i = 0; i < 20000; ++i) {
    Bytes d = reference;
    for (int k = 0; k < 1 + static_cast<int>(rng() % 4); ++k) {
      d[rng() % d.size()] = static_cast<std::uint8_t>(rng());
    }
    if (rng() % 4 == 0) d.resize(rng() % d.size());
    const auto p = parse_report_descriptor(d);
    if (!p.descriptor) {
      EXPECT_FALSE(p.error.empty());
      ++refused;
      continue;
    }
    ++parsed;
    const PidFind f = find_pid_layout(*p.descriptor, kGenericDesktopX, kReferenceSequenceUsage);
    if (!f.layout) {
      EXPECT_FALSE(f.error.empty());
      continue;
    }
    // Whatever was found can be written and read within its own report.
    Bytes r = make_report(f.layout->set_constant, true);
    set_slot(std::span<std::uint8_t>(r).subspan(1), f.layout->sc_magnitude, -1);
    EXPECT_EQ(r.size(), f.layout->set_constant.wire_size());
  }
  EXPECT_GT(parsed, 100);
  EXPECT_GT(refused, 100);
}

TEST(HidMalformed, RandomReportsNeverCrashTheSimulatedFirmware) {
  for (const char* example : {"hid-report.yaml", "hid-pid.yaml"}) {
    const config::Config cfg = testing::load_example(example);
    auto fw = sim::hid::make_firmware(cfg, 1);
    std::mt19937 rng(3);
    int answers = 0;
    const sim::hid::HidFirmware::Send count = [&](std::span<const std::uint8_t>) { ++answers; };
    for (int i = 0; i < 20000; ++i) {
      Bytes r(rng() % 24);
      for (auto& b : r) b = static_cast<std::uint8_t>(rng() % 4 == 0 ? rng() % 0x50 : rng());
      switch (rng() % 3) {
        case 0:
          fw->on_output(r, count);
          break;
        case 1:
          fw->on_set_feature(r, count);
          break;
        default: {
          Bytes out;
          fw->on_get_feature(static_cast<std::uint8_t>(rng()), out);
        }
      }
      ASSERT_TRUE(std::isfinite(fw->applied_force()));
    }
    SUCCEED() << example << ": " << answers << " answers";
  }
}

// The paths the conformance suite's loop never meets, on the tick: malformed reports of every
// kind counted, samples superseded, then a device that takes no more output reports until the
// full queue faults it. Not one allocation on the way.
TEST(HidMalformed, CountingBadReportsAndAFullQueueAllocateNothing) {
  const auto s = testing::settings_of(testing::load_example("hid-report.yaml"));
  testing::FakeHidDevice fake(report_profile_descriptor(s->report));
  HidDevice device(s, fake.opener(), 1e-3);
  device.configure();
  device.enable();
  Bytes good(input_report_size(s->report.input));
  encode_input({.position = {0.001}, .sequence = 1, .status = 0}, s->report.input, good);
  for (const Bytes& r :
       {Bytes{1, 2}, Bytes{9, 0, 0, 0, 0, 0, 0, 0, 0}, Bytes{}, Bytes(3000, 1), good, good}) {
    fake.send_input(r);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(10));
  fake.reading.store(false);
  PositionSample sample;
  IoStatus read = IoStatus::kNoNewData, written = IoStatus::kOk;
  int ticks = 0;
  const ::hapticd::testing::AllocationScope scope;
  read = device.read(sample);
  for (; written == IoStatus::kOk && ticks < 100000; ++ticks) written = device.write(1.0);
  const std::uint64_t allocations = scope.count();
  fake.reading.store(true);
  EXPECT_EQ(allocations, 0u) << "over " << ticks << " ticks";
  EXPECT_EQ(read, IoStatus::kOk);
  EXPECT_EQ(written, IoStatus::kTransportFault) << "the full queue faulted it in the end";
  const HidCounters c = device.hid_counts();
  EXPECT_EQ(c.too_short + c.unknown_id + c.too_long, 4u);
  EXPECT_EQ(c.superseded, 1u);
  EXPECT_EQ(c.out_queue_full, 10u);
}

}  // namespace
}  // namespace hapticd::drivers::hid
