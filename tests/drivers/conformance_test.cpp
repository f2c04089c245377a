// The conformance suite (docs/devices.md): every registered driver, with its loopback peer, must
// keep the lifecycle, command zero force on disable and on every fault class, detect stale
// data and sequence gaps, and never allocate in read/write, whatever the configuration. A
// driver joins by adding its example configurations to kCases; a registered driver without
// one fails EveryRegisteredDriverIsCovered.
#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "alloc_counter.h"
#include "config/config_loader.h"
#include "control/controller.h"
#include "control/direction_probe.h"
#include "loop/servo_loop.h"
#include "sim/peers/paced_device.h"
#include "sim/peers/peer_runner.h"
#include "wiring/registry.h"

namespace hapticd::drivers {
namespace {

struct Case {
  const char* driver;
  const char* config;  // relative to the source tree
  // --set on top of it, where the example lacks what is tested
  std::array<const char*, 2> sets{};
};

// Each driver's example configurations, run against its peer.
const Case kCases[] = {
    {"sim", "config/sim.yaml"},
#if HAPTICD_WITH_HID
    {"hid", "config/hid-report.yaml"},
    // Packed fields sharing a byte, and a position that wraps and is unwrapped (issue 34).
    {"hid",
     "config/hid-report.yaml",
     {"device.hid.report.input.position={byte: 4, bits: 12, signed: true, scale: 1.0e-5, "
      "wraps: true}",
      "device.hid.report.input.velocity={byte: 5, bit: 4, bits: 12, signed: true, scale: "
      "1.0e-3}"}},
    // The simulated PID device's sample counter, so a sequence gap can be injected.
    {"hid", "config/hid-pid.yaml", {"device.hid.pid.sequence={usage_page: 0xff00, usage: 0x20}"}},
#endif
#if HAPTICD_WITH_CAN
    {"can", "config/can-cia402.yaml"},
    {"can", "config/can-odrive.yaml"},
#endif
#if HAPTICD_WITH_GPIO
    {"gpio", "config/gpio.yaml"},
#endif
#if HAPTICD_WITH_EVDEV
    // A bound on silence, so a device that stops answering is stale data (evdev's default has
    // none: a device held still is silent too); a full scale whose levels are exact binary
    // fractions (2^-11 N), so the forces the suite writes reach the device unrounded.
    {"evdev",
     "config/evdev.yaml",
     {"device.evdev.liveness_ms=100", "device.evdev.force_full_scale=15.99951171875"}},
#endif
#if HAPTICD_WITH_SERIAL
    {"serial", "config/serial-stream.yaml"},
#endif
};

config::Config load(const Case& c, const std::vector<std::string>& sets = {}) {
  const std::string path = std::string(HAPTICD_SOURCE_DIR) + "/" + c.config;
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::vector<config::Override> overrides;
  // A loaded host can hold the in-process drive past the examples' 100 ms SDO wait (can_rig.h).
  if (std::string_view(c.driver) == "can") {
    overrides.push_back(config::parse_override("device.can.sdo_timeout_ms=2000"));
  }
  for (const char* set : c.sets) {
    if (set != nullptr) overrides.push_back(config::parse_override(set));
  }
  for (const std::string& s : sets) overrides.push_back(config::parse_override(s));
  overrides.push_back(config::parse_override("loop.clock=freerun"));
  return config::load_config_text(text.str(), path, overrides, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

// The driver configured by `driver_cfg` against the simulated device of `device_cfg`: what a
// setting changed on the host does to the same physical device (the sim, in process, has one
// configuration: the driver's).
wiring::Loopback pair_of(const config::Config& driver_cfg, const config::Config& device_cfg) {
  const wiring::DriverEntry& d = wiring::find_driver(driver_cfg.device.driver);
  if (d.make_in_process != nullptr) return d.make_in_process(driver_cfg);
  auto [device_end, peer_end] = io::seqpacket_pair();
  wiring::Loopback pair;
  pair.peer = d.peer.make_peer(device_cfg, std::move(peer_end));
  pair.device = d.make_loopback_device(driver_cfg, std::move(device_end));
  return pair;
}

// The driver wired to its peer, the peer on its own thread, paced as in a freerun run.
struct Rig {
  explicit Rig(const config::Config& c) : Rig(c, c) {}
  Rig(const config::Config& c, const config::Config& device_cfg)
      : cfg(c),
        pair(pair_of(c, device_cfg)),
        runner(*pair.peer),
        device(std::move(pair.device), runner) {}
  ~Rig() { device.close(); }
  sim::LoopbackPeer& peer() { return *pair.peer; }
  // Every force written so far has reached the peer.
  void settle() { runner.wait_idle(); }

  config::Config cfg;
  wiring::Loopback pair;
  sim::PeerRunner runner;
  sim::PacedDevice device;
};

// Runs the servo loop in freerun; `allocations`, when given, counts the loop's own (everything
// it needs is built before).
loop::LoopResult run_loop(Rig& rig, std::uint64_t ticks, loop::LoopOptions o = {},
                          std::uint64_t* allocations = nullptr) {
  control::Controller controller(control::make_control_law(rig.cfg));
  o.sample.realtime = false;
  o.sample.period_ns = std::llround(rig.cfg.loop.sample_period_s() * 1e9);
  o.max_ticks = ticks;
  o.sample.stale_fault_ticks = rig.cfg.safety.stale_fault_ticks;
  o.sample.max_speed = rig.cfg.safety.max_speed;
  o.sample.sequence_modulus = rig.device.info().sequence_modulus;
  loop::ServoLoop servo(rig.device, controller, nullptr, o);
  const std::atomic<bool> stop{false};
  const testing::AllocationScope scope;
  const loop::LoopResult r = servo.run(stop);
  if (allocations != nullptr) *allocations = scope.count();
  return r;
}

class Conformance : public ::testing::TestWithParam<Case> {};

TEST_P(Conformance, LifecycleIsEnforcedAndOutputFollowsIt) {
  Rig rig(load(GetParam()));
  Device& d = rig.device;
  PositionSample s;
  EXPECT_EQ(d.read(s), IoStatus::kTransportFault) << "nothing is open before configure";
  EXPECT_THROW(d.enable(), DeviceError);
  d.configure();
  EXPECT_EQ(d.state(), DeviceState::kConfigured);
  EXPECT_EQ(d.info().transport_delay_samples,
            wiring::find_driver(rig.cfg.device.driver).declared_delay(rig.cfg))
      << "the device must declare what `check` analyses";
  EXPECT_EQ(d.write(2.0), IoStatus::kTransportFault) << "no force before enable";
  rig.settle();
  EXPECT_FALSE(rig.peer().output_on());
  EXPECT_EQ(rig.peer().applied_force(), 0.0);
  d.enable();
  EXPECT_EQ(d.write(2.0), IoStatus::kOk);
  rig.settle();
  EXPECT_TRUE(rig.peer().output_on());
  EXPECT_NE(rig.peer().applied_force(), 0.0);
  EXPECT_THROW(d.configure(), DeviceError);
  d.disable();
  rig.settle();
  EXPECT_EQ(d.state(), DeviceState::kConfigured);
  EXPECT_FALSE(rig.peer().output_on()) << "disable must switch the amplifier off";
  EXPECT_EQ(rig.peer().applied_force(), 0.0) << "disable must leave zero force";
  d.close();
  EXPECT_EQ(d.state(), DeviceState::kUnconfigured);
}

// A fault the device reports, or a failing transport, injected while a force is applied:
// zero reaches the device at the very read that sees it, before anyone writes again, and the
// latched fault passes nothing but zero until clear_fault.
TEST_P(Conformance, DeviceAndTransportFaultsCommandZeroAtOnce) {
  const std::pair<sim::PeerFault, IoStatus> faults[] = {
      {sim::PeerFault::kDeviceFault, IoStatus::kDeviceFault},
      {sim::PeerFault::kTransportFault, IoStatus::kTransportFault}};
  for (const auto& [fault, status] : faults) {
    SCOPED_TRACE(std::string(sim::to_string(fault)));
    Rig rig(load(GetParam()));
    Device& d = rig.device;
    d.configure();
    d.enable();
    PositionSample s;
    d.read(s);
    ASSERT_EQ(d.write(3.0), IoStatus::kOk);
    rig.settle();
    ASSERT_EQ(rig.peer().applied_force(), 3.0);
    ASSERT_TRUE(rig.peer().inject(fault));
    IoStatus seen = IoStatus::kOk;
    for (int tick = 0; tick < 20 && (seen == IoStatus::kOk || seen == IoStatus::kNoNewData);
         ++tick) {
      seen = d.read(s);
      rig.settle();
      if (seen == IoStatus::kOk || seen == IoStatus::kNoNewData) {
        seen = d.write(3.0);
      } else {
        EXPECT_EQ(rig.peer().applied_force(), 0.0) << "zero before any further write";
      }
    }
    EXPECT_EQ(seen, status);
    EXPECT_EQ(d.state(), DeviceState::kFaulted);
    EXPECT_EQ(d.fault().fault_class,
              status == IoStatus::kDeviceFault ? FaultClass::kDevice : FaultClass::kTransport);
    EXPECT_EQ(d.last_command(), 0.0);
    EXPECT_NE(d.write(3.0), IoStatus::kOk) << "latched";
    rig.settle();
    EXPECT_EQ(rig.peer().applied_force(), 0.0);
    d.disable();
    rig.settle();
    EXPECT_EQ(d.state(), DeviceState::kFaulted) << "disable does not clear a fault";
    EXPECT_FALSE(rig.peer().output_on());
    EXPECT_FALSE(d.describe_fault().empty());
  }
}

// Every fault class as the loop meets it, injected mid-run while the wall pushes: the loop
// faults with the right cause and the device is left with zero force.
TEST_P(Conformance, EveryFaultClassFaultsTheLoopWithZeroForce) {
  const std::pair<sim::PeerFault, loop::FaultCause> faults[] = {
      {sim::PeerFault::kDeviceFault, loop::FaultCause::kDeviceReported},
      {sim::PeerFault::kTransportFault, loop::FaultCause::kTransportRead},
      {sim::PeerFault::kStopAnswering, loop::FaultCause::kStaleData},
      {sim::PeerFault::kSkipSequence, loop::FaultCause::kSequenceGap}};
  for (const auto& [fault, cause] : faults) {
    SCOPED_TRACE(std::string(sim::to_string(fault)));
    // Start outside, pushed in by a constant force, so the wall pushes when the fault strikes.
    Rig rig(load(GetParam(), {"device.sim.initial_position=-0.0005",
                              "device.sim.operator={kind: force, force: {shape: constant, "
                              "value: 3}}"}));
    rig.device.configure();
    rig.device.enable();
    control::Controller controller(control::make_control_law(rig.cfg));
    loop::LoopOptions o;
    o.sample.realtime = false;
    o.sample.period_ns = std::llround(rig.cfg.loop.sample_period_s() * 1e9);
    o.max_ticks = 2'000'000;  // ends by the fault long before
    o.sample.sequence_gap_fault = 1;
    o.sample.sequence_modulus = rig.device.info().sequence_modulus;
    loop::ServoLoop servo(rig.device, controller, nullptr, o);
    const std::atomic<bool> stop{false};
    loop::LoopResult r;
    std::atomic<bool> ended{false};
    std::thread t([&] {
      r = servo.run(stop);
      ended = true;
    });
    while (servo.ticks_done() < 500 && !ended) std::this_thread::yield();
    if (ended) {  // a loop that ended by itself cannot meet the fault: say why it ended
      t.join();
      ADD_FAILURE() << "the loop ended before the fault: " << loop::describe(r.fault);
      continue;
    }
    const bool expressible = rig.peer().inject(fault);
    if (!expressible) rig.peer().inject(sim::PeerFault::kTransportFault);  // end the run
    t.join();
    if (!expressible) {
      // Only a sequence gap may be inexpressible, and only on a transport that numbers nothing
      // (the loop's gap check is then off): anything else is a peer that cannot test a fault.
      EXPECT_EQ(fault, sim::PeerFault::kSkipSequence) << GetParam().driver;
      EXPECT_EQ(rig.device.info().sequence_modulus, 0u)
          << GetParam().driver << " numbers its samples, but its peer cannot skip one";
      continue;
    }
    // A broken transport faults whichever direction meets it first: a read of data still
    // buffered can succeed and the write after it fail (the GPIO loopback does that).
    const bool either_direction = cause == loop::FaultCause::kTransportRead &&
                                  r.fault.cause == loop::FaultCause::kTransportWrite;
    if (!either_direction) {
      EXPECT_EQ(r.fault.cause, cause) << loop::describe(r.fault);
    }
    EXPECT_GT(r.count(loop::kCounterContactTicks), 100u)
        << "the wall was pushing when the fault struck";
    rig.settle();
    EXPECT_EQ(rig.peer().applied_force(), 0.0);
    EXPECT_EQ(rig.device.last_command(), 0.0);
    rig.device.disable();
    rig.settle();
    EXPECT_FALSE(rig.peer().output_on());
  }
}

// Thousands of ticks through read/write, for each shape of configuration the controller and
// the device support, and through the fault path: not one allocation on the loop's thread.
TEST_P(Conformance, ReadAndWriteNeverAllocate) {
  const std::vector<std::vector<std::string>> shapes = {
      {},
      {"wall.coupling={numerator: [0.1, -0.0752, 0.0016, -0.0101], "
       "denominator: [1, -1.8407, 0.8444, -0.0037]}",
       "safety.gate=warn"},
      {"wall.delay_samples=7", "wall.discretization=tustin"},
      {"device.sim.noise_counts=2", "device.sim.seed=5", "wall.no_pull=true"},
  };
  for (const auto& shape : shapes) {
    SCOPED_TRACE(shape.empty() ? "default" : shape.front());
    Rig rig(load(GetParam(), shape));
    rig.device.configure();
    rig.device.enable();
    std::uint64_t allocations = 1;
    const loop::LoopResult r = run_loop(rig, 5000, {}, &allocations);
    EXPECT_EQ(allocations, 0u) << "allocations on the RT path over " << r.ticks << " ticks";
    EXPECT_EQ(r.fault.cause, loop::FaultCause::kNone) << loop::describe(r.fault);
    EXPECT_GT(r.count(loop::kCounterContactTicks), 0u) << "the demo presses into the wall";
  }
  Rig rig(load(GetParam()));
  rig.device.configure();
  rig.device.enable();
  run_loop(rig, 100);
  ASSERT_TRUE(rig.peer().inject(sim::PeerFault::kDeviceFault));
  std::uint64_t allocations = 1;
  const loop::LoopResult r = run_loop(rig, 100, {}, &allocations);
  EXPECT_EQ(allocations, 0u) << "on the fault path";
  EXPECT_EQ(r.fault.cause, loop::FaultCause::kDeviceReported);
}

// The loop as `hapticd run` sets it up: the direction check of the configuration before the
// wall is armed (off in the LoopOptions the other cases build).
loop::LoopOptions checked(const Rig& rig) {
  loop::LoopOptions o;
  o.probe = control::probe_plan(rig.cfg, rig.device.info().transport_delay_samples);
  o.refuse_no_motion = true;
  return o;
}

// A force as the example configures it is confirmed, and the wall then acts as always; the
// same device with its motor wired the other way round is refused before the wall ever acts.
TEST_P(Conformance, TheDirectionCheckConfirmsTheForceAndRefusesItReversed) {
  for (const bool reversed : {false, true}) {
    SCOPED_TRACE(reversed ? "reversed" : "as configured");
    Rig rig(load(GetParam(), {reversed ? "device.sim.force_reversed=true" : "device.sim.seed=1"}));
    rig.device.configure();
    rig.device.enable();
    std::uint64_t allocations = 1;
    const loop::LoopResult r = run_loop(rig, 3000, checked(rig), &allocations);
    EXPECT_EQ(allocations, 0u) << "the check allocates nothing either";
    if (reversed) {
      EXPECT_EQ(r.direction.state, control::ProbeState::kReversed) << r.direction.gain;
      EXPECT_EQ(r.fault.cause, loop::FaultCause::kForceReversed) << loop::describe(r.fault);
      EXPECT_LT(r.direction.gain, -0.2);
      EXPECT_EQ(r.count(loop::kCounterContactTicks), 0u) << "no wall acted";
      rig.settle();
      EXPECT_EQ(rig.peer().applied_force(), 0.0);
      EXPECT_EQ(rig.device.last_command(), 0.0);
    } else {
      EXPECT_EQ(r.direction.state, control::ProbeState::kConfirmed) << r.direction.gain;
      EXPECT_EQ(r.fault.cause, loop::FaultCause::kNone) << loop::describe(r.fault);
      EXPECT_GT(r.direction.gain, 0.2);
      EXPECT_GT(r.count(loop::kCounterContactTicks), 0u)
          << "the demo presses into the wall once it is armed";
    }
  }
}

// With the check off, the reversed wall pulls the device in until it saturates; the runaway
// guard faults before the penetration passes its bound by more than a tick's motion, with
// zero force.
TEST_P(Conformance, TheRunawayGuardStopsAReversedWallWithTheCheckOff) {
  Rig rig(load(GetParam(), {"device.sim.force_reversed=true"}));
  rig.device.configure();
  rig.device.enable();
  const loop::LoopResult r = run_loop(rig, 20000);
  ASSERT_EQ(r.fault.cause, loop::FaultCause::kRunaway) << loop::describe(r.fault);
  const double bound = control::runaway_penetration(rig.cfg);
  EXPECT_DOUBLE_EQ(r.fault.limit, bound);
  EXPECT_GT(r.fault.value, bound);
  // At the speed the saturated force can give the device over the run, one tick's travel.
  EXPECT_LT(r.max_penetration, bound * 1.2) << "caught within its bound";
  rig.settle();
  EXPECT_EQ(rig.peer().applied_force(), 0.0);
  EXPECT_EQ(rig.device.last_command(), 0.0);
}

// The setting the check names for a reversed force reverses what the device feels.
TEST_P(Conformance, TheDriversReversalSettingReversesTheForceTheDeviceFeels) {
  const config::Config plain = load(GetParam());
  const wiring::DriverEntry& driver = wiring::find_driver(plain.device.driver);
  ASSERT_NE(driver.force_reversal, nullptr) << "every driver names its reversal";
  const ForceReversal f = driver.force_reversal(plain);
  EXPECT_NE(f.now, f.reversed);
  for (const bool flip : {false, true}) {
    SCOPED_TRACE(flip ? f.key + ": " + f.reversed : "as configured");
    // The driver with the setting, the simulated device as it was: the same motor.
    Rig rig(load(GetParam(), {flip ? f.key + "=" + f.reversed : "device.sim.seed=1"}), plain);
    rig.device.configure();
    rig.device.enable();
    PositionSample s;
    rig.device.read(s);
    ASSERT_EQ(rig.device.write(2.0), IoStatus::kOk);
    rig.settle();
    EXPECT_NEAR(rig.peer().applied_force(), flip ? -2.0 : 2.0, 0.01);
  }
}

std::string case_name(const ::testing::TestParamInfo<Case>& p) {
  return std::string(p.param.driver) + "_" + std::to_string(p.index);
}

INSTANTIATE_TEST_SUITE_P(Drivers, Conformance, ::testing::ValuesIn(kCases), case_name);

// The Falcon has three joints and no configuration of one: its lifecycle, faults and force
// reversal are proven in tests/falcon/ against the same simulated device, and its run of several
// joints in joints_conformance_test.cpp.
constexpr const char* kSeveralJointsOnly[] = {"falcon"};

TEST(Conformance, EveryRegisteredDriverIsCovered) {
  for (const wiring::DriverEntry& d : wiring::registered_drivers()) {
    bool covered = false;
    for (const Case& c : kCases) covered = covered || d.name == c.driver;
    for (const char* name : kSeveralJointsOnly) covered = covered || d.name == name;
    EXPECT_TRUE(covered) << "driver '" << d.name << "' has no conformance case";
  }
}

}  // namespace
}  // namespace hapticd::drivers
