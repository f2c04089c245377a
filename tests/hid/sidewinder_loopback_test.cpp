// The HID driver against the simulated PID device as the SideWinder-lineage firmwares are
// (sim/peers/hid/hid_firmwares.h, PidFirmwareOptions::sidewinder_lineage: Device Control a
// 0x96 collection alone, ids shared between kinds, PID State declared and never sent, Block
// Load answered once, +sin(direction)), with config/hid-arduino-ffb.yaml in freerun: the
// direction check confirms the force's sign, no PID State bit faults (it never sends one),
// and the wall is the sim driver's with the same delay.
#include <gtest/gtest.h>

#include <cmath>

#include "control/controller.h"
#include "control/direction_probe.h"
#include "drivers/io/unique_fd.h"
#include "hid_test_support.h"
#include "loop/servo_loop.h"
#include "sim/peers/hid/hid_firmwares.h"
#include "sim/peers/hid/socket_hid_peer.h"
#include "sim/peers/paced_device.h"
#include "sim/peers/peer_runner.h"

namespace hapticd::drivers::hid {
namespace {

struct Outcome {
  loop::LoopResult result;
  std::string fault;
  bool peer_on_after = true;
  std::uint64_t state_reports = 1;
};

// `sidewinder`: the HID driver against the SideWinder-lineage simulated device; otherwise the
// sim driver on the same plant and wall with the HID driver's declared delay.
Outcome run(bool sidewinder) {
  std::vector<std::string> sets = {"loop.clock=freerun", "device.sim.force_reversed=false"};
  if (sidewinder) {
    // Every PID State bit under the mask: a device that never sends one faults on none.
    sets.push_back("device.hid.pid.fault_mask=0x3f");
  } else {
    sets.insert(sets.end(), {"device.driver=sim", "device.hid=", "wall.delay_samples=1"});
  }
  const config::Config cfg = testing::load_example("hid-arduino-ffb.yaml", sets);
  std::unique_ptr<Device> inner;
  std::unique_ptr<sim::LoopbackPeer> peer;
  if (sidewinder) {
    auto [host, far] = io::seqpacket_pair();
    inner = wiring::find_driver("hid").make_loopback_device(cfg, std::move(host));
    peer = std::make_unique<sim::hid::SocketHidPeer>(
        std::move(far), sim::hid::make_pid_firmware(cfg, *testing::settings_of(cfg), 1,
                                                    {.sidewinder_lineage = true}));
  } else {
    wiring::Loopback pair = wiring::find_driver("sim").make_loopback(cfg);
    inner = std::move(pair.device);
    peer = std::move(pair.peer);
  }
  Outcome out;
  sim::PeerRunner runner(*peer);
  sim::PacedDevice device(std::move(inner), runner);
  device.configure();
  device.enable();
  control::Controller controller(control::make_control_law(cfg));
  loop::LoopOptions o;
  o.sample.realtime = false;
  o.sample.period_ns = std::llround(cfg.loop.sample_period_s() * 1e9);
  o.max_ticks = 3000;
  o.sample.stale_fault_ticks = cfg.safety.stale_fault_ticks;
  o.sample.sequence_gap_fault = cfg.safety.sequence_gap_fault;
  o.probe = control::probe_plan(cfg, 1);
  loop::ServoLoop servo(device, controller, nullptr, o);
  const std::atomic<bool> stop{false};
  out.result = servo.run(stop);
  out.fault = loop::describe(out.result.fault) + "; " + device.describe_fault();
  for (const base::Counter& c : device.counters()) {
    if (c.name() == std::string_view("state_reports")) out.state_reports = c.value();
  }
  device.disable();
  runner.wait_idle();
  out.peer_on_after = peer->output_on();
  device.close();
  return out;
}

TEST(HidPidSideWinder, ALibraryClassDeviceRendersTheSimDriversWall) {
  const Outcome hid = run(true);
  const Outcome sim = run(false);
  ASSERT_EQ(hid.result.fault.cause, loop::FaultCause::kNone) << hid.fault;
  ASSERT_EQ(sim.result.fault.cause, loop::FaultCause::kNone) << sim.fault;
  EXPECT_EQ(hid.result.direction.state, control::ProbeState::kConfirmed)
      << "direction_deg 90 pushes toward +X on a +sin firmware";
  EXPECT_GT(hid.result.count(loop::kCounterContactTicks), 1000u);
  EXPECT_NEAR(hid.result.max_penetration, sim.result.max_penetration,
              0.01 * sim.result.max_penetration);
  EXPECT_EQ(hid.state_reports, 0u) << "it never sends PID State";
  EXPECT_FALSE(hid.peer_on_after);
}

}  // namespace
}  // namespace hapticd::drivers::hid
