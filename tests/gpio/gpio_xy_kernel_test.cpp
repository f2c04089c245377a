// The GPIO driver of several joints on the kernel's own interfaces, in the kernel test machine:
// config/gpio-xy.yaml's two joints, each with its quadrature encoder, direction and fault lines
// on a gpio-sim chip of its own (two chips: one line request and one read a tick each with
// libgpiod 2.x) and its own channel of hapticd's PWM simulator, hapticd run as a user runs it
// against the driver's peer there (make_peer_on: one encoder and motor driver per joint, moving
// one simulated XY table). The hand pressed along the diagonal rests at F/K along the wall's
// normal (1, 1)/sqrt 2; unplugging joint 1's chip and corrupting joint 1's encoder each end the
// run with zero duty on both channels and the cause naming joint 1; a silenced encoder (no more
// edges while force is applied) cannot be told from a still shaft, and the run says what it
// can. The loop's system calls a tick are counted under strace (tests/reference/rt_syscalls.h).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <climits>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "../reference/rt_syscalls.h"
#include "config/config_loader.h"
#include "gpio_sim_chip.h"
#include "pwm_sim.h"
#include "sim/peers/gpio/gpio_peer.h"
#include "sim/peers/peer_runner.h"
#include "sysfs.h"
#include "wiring/registry.h"

namespace hapticd::drivers::gpio {
namespace {

using kernel_test::GpioSimChip;
using kernel_test::PwmSim;
using namespace std::chrono_literals;

// As tests/gpio/gpio_kernel_test.cpp explains for one joint (what the emulated guest sustains):
// 50 Hz, the wall at 150 N/m (b_req 1.7 <= 1.8 N s/m), 0.5 mm counts, max_edge_rate 25, edges
// put 80 ms apart at least on each joint's lines. The press: the wall's face 2.83 mm from the
// origin along the diagonal (the table starts 0.35 mm along it), the hand's set-point 47.5 mm
// along it over 10 s (each joint moves about 23 mm, 46 counts: 4.6 edges/s), held past the
// run's end. At rest the hand (300 N/m) and the wall share its reach past the face, 45.0 mm:
// p = 300 x 45.0 / 450 = 30.0 mm, F = 4.5 N; 2 % of it is 0.6 mm, above what the joints' 0.5 mm
// counts can move the rest along the normal (the plant rests where the hand balances the
// quantised wall: the measured penetration within 2/3 x 0.71 mm of p).
const std::vector<std::string> kXySets = {
    "loop.rate_hz=50", "walls[0].stiffness=150", "walls[0].point=[0.002, 0.002]",
    "device.gpio.counts_per_unit=2000", "device.sim.counts_per_unit=2000",
    "device.gpio.max_edge_rate=25", "loop.overrun_fault_streak=50", "safety.stale_fault_ticks=10",
    // Mid-count (0.25 mm: count 0, the lines at 00 where gpio-sim leaves them), so the plant at
    // rest does not dither across a count boundary before the press.
    "device.sim.operator.origin=[0.00025, 0.00025]", "device.sim.operator.setpoint.depth=0.0475",
    "device.sim.operator.setpoint.start=2", "device.sim.operator.setpoint.ramp=10",
    "device.sim.operator.setpoint.hold=60"};

// Joint 0 on one gpio-sim chip, joint 1 on another, both channels of the PWM simulator.
struct XyMachine {
  GpioSimChip x{4, "hapticd-gpio-x", {}, "hapticd-x"};
  GpioSimChip y{4, "hapticd-gpio-y", {}, "hapticd-y"};
  PwmSim pwm;

  static std::string dir_of(const GpioSimChip& chip) {
    char buf[PATH_MAX];
    const std::string link = "/sys/bus/gpio/devices/" + chip.chip_name();
    if (realpath(link.c_str(), buf) == nullptr) throw std::runtime_error("no " + link);
    return buf;
  }
  unsigned pwm_chip() const {
    const std::string p = pwm.chip_path();
    return static_cast<unsigned>(std::stoul(p.substr(p.rfind("pwmchip") + 7)));
  }
  // config/gpio-xy.yaml adapted to the guest's chips: what a user with these chips would set.
  std::vector<std::string> sets() const {
    std::vector<std::string> s = kXySets;
    s.push_back("device.gpio.chip=" + x.chip_name());
    s.push_back("device.gpio.joints[1].chip=" + y.chip_name());
    s.push_back("device.gpio.joints[1].lines={a: 0, b: 1, direction: 2, fault: 3}");
    s.push_back("device.gpio.pwm.chip=" + std::to_string(pwm_chip()));
    return s;
  }
  std::string endpoint() const {
    return dir_of(x) + ",/sys/devices/platform/hapticd-pwm-sim/channel0;" + dir_of(y) +
           ",/sys/devices/platform/hapticd-pwm-sim/channel1";
  }
};

config::Config load_xy_guest(const std::vector<std::string>& sets) {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/gpio-xy.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::vector<config::Override> o;
  for (const auto& s : sets) o.push_back(config::parse_override(s));
  return config::load_config_text(text.str(), "config/gpio-xy.yaml", o,
                                  HAPTICD_SOURCE_DIR "/config", wiring::driver_schemas());
}

std::string read_all(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

struct XyRun {
  int exit_code = -1;
  nlohmann::json summary;
  std::string output;
  std::string dir;  // its log (run.hlog), summary and output
};

// `hapticd run --config config/gpio-xy.yaml` with the guest's chips, under `wrap` (strace, or
// nothing); the peer started once the gate passed (the channels are on at duty 0 from
// configure), `strike` called with it once the wall pushes.
XyRun run_xy(const XyMachine& m, double duration_s, const std::vector<std::string>& extra,
             const std::vector<std::string>& wrap,
             const std::function<sim::gpio::GpioPeer&()>& start_peer,
             const std::function<void(sim::gpio::GpioPeer&)>& strike) {
  XyRun r;
  r.dir = "/tmp/hapticd-gpio-xy-kt-" + std::to_string(getpid());
  mkdir(r.dir.c_str(), 0755);
  std::vector<std::string> args = wrap;
  for (const std::string& a :
       {std::string(HAPTICD_BINARY), std::string("run"), std::string("--config"),
        std::string(HAPTICD_SOURCE_DIR "/config/gpio-xy.yaml"), std::string("--duration"),
        std::to_string(duration_s), std::string("--log"), r.dir + "/run.hlog",
        std::string("--summary-json"), r.dir + "/summary.json"}) {
    args.push_back(a);
  }
  for (const auto& s : m.sets()) args.insert(args.end(), {"--set", s});
  for (const auto& s : extra) args.insert(args.end(), {"--set", s});
  const std::string out = r.dir + "/output.txt";
  unlink(out.c_str());
  unlink((r.dir + "/summary.json").c_str());
  const pid_t pid = fork();
  if (pid == 0) {
    freopen(out.c_str(), "w", stdout);
    dup2(fileno(stdout), 2);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  bool exited = false;
  const auto until = std::chrono::steady_clock::now() + 120s;
  const auto running = [&] {
    return std::chrono::steady_clock::now() < until &&
           !(exited = waitpid(pid, &status, WNOHANG) == pid);
  };
  const auto logged = [&](const char* w) { return read_all(out).find(w) != std::string::npos; };
  while (running() && !logged("gate: pass")) std::this_thread::sleep_for(5ms);
  if (!exited) {
    sim::gpio::GpioPeer& peer = start_peer();
    if (strike) {
      while (!logged("output enabled") && running()) std::this_thread::sleep_for(5ms);
      // Once the wall pushes: the hand is in contact, both motors driven.
      while (running() && (peer.duty_ns(0) == 0 || peer.duty_ns(1) == 0 ||
                           std::abs(peer.applied_force()) < 1.0)) {
        std::this_thread::sleep_for(5ms);
      }
      EXPECT_GE(std::abs(peer.applied_force()), 1.0) << "the wall never pushed";
      strike(peer);
    }
  }
  if (!exited) waitpid(pid, &status, 0);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.output = read_all(out);
  std::ifstream js(r.dir + "/summary.json");
  if (js) r.summary = nlohmann::json::parse(js, nullptr, false);
  return r;
}

// The penetration of the last `ticks` records of the run's tick log, averaged.
double rest_penetration(const XyRun& r, std::size_t ticks) {
  const std::string csv = r.dir + "/run.csv";
  const std::string cmd =
      std::string(HAPTICD_BINARY) + " export " + r.dir + "/run.hlog --out " + csv;
  if (std::system(cmd.c_str()) != 0) return -1.0;
  std::ifstream in(csv);
  std::vector<double> p;
  std::string line;
  std::getline(in, line);  // the header: penetration is the sixth column
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string f;
    for (int i = 0; i < 6 && std::getline(fields, f, ','); ++i) {
    }
    p.push_back(std::stod(f));
  }
  if (p.size() < ticks) return -1.0;
  double sum = 0.0;
  for (std::size_t k = p.size() - ticks; k < p.size(); ++k) sum += p[k];
  return sum / static_cast<double>(ticks);
}

class GpioXyKernelRun : public testing::Test {
 protected:
  void SetUp() override {
    cfg_ = std::make_unique<config::Config>(load_xy_guest(m_.sets()));
    m_.x.set_pull(3, true);  // both nFAULTs released: hapticd configures before the peer is there
    m_.y.set_pull(3, true);
  }
  void TearDown() override {
    if (!runner_) return;
    runner_->stop();
    // An unplugged chip's lines cannot be pulled any more: the peer says so and stops.
    if (!unplugged_) {
      EXPECT_EQ(runner_->error(), "");
    }
  }
  // `extra`: further --set, the peer's configuration too.
  XyRun run(double duration_s, const std::function<void(sim::gpio::GpioPeer&)>& strike,
            const std::vector<std::string>& wrap = {}, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> sets = m_.sets();
    sets.insert(sets.end(), extra.begin(), extra.end());
    cfg_ = std::make_unique<config::Config>(load_xy_guest(sets));
    return run_xy(
        m_, duration_s, extra, wrap,
        [this]() -> sim::gpio::GpioPeer& {
          auto peer = wiring::find_driver("gpio").peer.make_peer_on(*cfg_, m_.endpoint());
          peer_.reset(dynamic_cast<sim::gpio::GpioPeer*>(peer.release()));
          runner_ = std::make_unique<sim::PeerRunner>(*peer_, 50);
          return *peer_;
        },
        strike);
  }
  // Both channels at duty 0 and still enabled: every stop.
  void expect_both_stopped() {
    for (unsigned ch : {0u, 1u}) {
      EXPECT_EQ(m_.pwm.applied(ch).duty_cycle_ns, 0u) << "channel " << ch;
      EXPECT_TRUE(m_.pwm.applied(ch).enabled) << "channel " << ch;
    }
  }
  XyMachine m_;
  bool unplugged_ = false;
  std::unique_ptr<config::Config> cfg_;
  std::unique_ptr<sim::gpio::GpioPeer> peer_;
  std::unique_ptr<sim::PeerRunner> runner_;
};

TEST_F(GpioXyKernelRun, TwoEncodersTwoChannelsRestAtForceOverStiffnessAlongTheDiagonal) {
  const XyRun r = run(20.0, nullptr);
  std::cout << r.output;
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(r.summary.is_object()) << r.output;
  EXPECT_EQ(r.summary["faults"].size(), 0u) << r.output;
  EXPECT_GT(r.summary["counters"]["loop"]["contact_ticks"].get<double>(), 100.0) << r.output;
  const config::TaskWallConfig& wall = cfg_->walls.front();
  const config::OperatorSpec& hand = cfg_->device.sim.op;
  const double reach = 0.0475 - wall.normal.dot(wall.point - hand.origin);
  const double expected = hand.stiffness * reach / (wall.law.stiffness + hand.stiffness);
  const double rest = rest_penetration(r, 50);  // the last second
  std::cout << "rest penetration " << rest * 1e3 << " mm, F/K " << expected * 1e3 << " mm\n";
  EXPECT_NEAR(rest, expected, 0.02 * expected) << "F/K along the diagonal";
  expect_both_stopped();
}

// The loop's thread under strace (rt_syscalls.h): what it asks of the kernel each tick, and
// what reaches each PWM channel. strace stops the thread at every call, milliseconds each in
// the emulator: 10 Hz (the wall at 20 N/m for the gate), where a tick's calls fit its period.
// libgpiod 1.6 reads each input line's descriptor once a tick (A, B and the fault line of two
// joints: 6), 2.x each chip's request once (2 chips); a duty is written only when it changed.
TEST_F(GpioXyKernelRun, TheLoopsSystemCallsATick) {
  const std::string prefix = "/tmp/hapticd-gpio-xy-strace";
  const std::array<std::uint64_t, 2> before = {m_.pwm.applied(0).applies,
                                               m_.pwm.applied(1).applies};
  const XyRun r =
      run(8.0, nullptr, reference::strace_to(prefix), {"loop.rate_hz=10", "walls[0].stiffness=20"});
  std::cout << r.output;
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const reference::TickCalls calls = reference::tick_calls(prefix, 10);
  RecordProperty("rt_syscalls", reference::describe(calls));
  std::cout << "loop thread, per tick: " << reference::describe(calls) << "\n";
  ASSERT_GT(calls.ticks, 30);
  const auto per_tick = [&](const char* name) {
    const auto it = calls.per_tick.find(name);
    return it == calls.per_tick.end() ? 0.0 : it->second;
  };
  EXPECT_NEAR(per_tick("read"), HAPTICD_GPIOD_API == 1 ? 6.0 : 2.0, 0.05);
  EXPECT_LE(per_tick("write"), 2.0) << "a duty write per joint at most";
  const double ticks = r.summary["ticks"].get<double>();
  for (unsigned ch : {0u, 1u}) {
    const double applied = static_cast<double>(m_.pwm.applied(ch).applies - before[ch]);
    std::cout << "channel " << ch << ": " << applied / ticks << " PWM applies a tick\n";
    EXPECT_LE(applied, ticks + 8) << "at most one duty a tick (and set-up's and the stop's)";
  }
}

TEST_F(GpioXyKernelRun, UnpluggingJointOnesChipZeroesBothAndNamesIt) {
  const XyRun r = run(40.0, [this](sim::gpio::GpioPeer&) {
    unplugged_ = true;
    kernel_test::write_text("/sys/kernel/config/gpio-sim/hapticd-y/live", "0");
  });
  std::cout << r.output;
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("gpio: joint 1 ("), std::string::npos) << r.output;
  expect_both_stopped();
}

TEST_F(GpioXyKernelRun, IllegalTransitionsOnJointOneZeroBothAndNameIt) {
  const XyRun r = run(40.0, [](sim::gpio::GpioPeer& peer) {
    EXPECT_TRUE(peer.inject_wire(sim::gpio::WireFault::kIllegalPattern, 1));
  });
  std::cout << r.output;
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("gpio: joint 1 ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("illegal transitions"), std::string::npos) << r.output;
  expect_both_stopped();
}

TEST_F(GpioXyKernelRun, AnEdgeStormOnJointZeroZeroesBothAndNamesIt) {
  const XyRun r = run(40.0, [](sim::gpio::GpioPeer& peer) {
    EXPECT_TRUE(peer.inject_wire(sim::gpio::WireFault::kEdgeBurst, 0));
  });
  std::cout << r.output;
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("gpio: joint 0 ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("faster than device.gpio.max_edge_rate"), std::string::npos) << r.output;
  expect_both_stopped();
}

// Silenced: the encoders stop while the motors push (the peer puts no more edges on the wires;
// the plant moves on under the hand). A quadrature encoder says only that the shaft moved: no
// edges is a still shaft or a dead encoder, and nothing on the lines tells them apart (no
// heartbeat, no sequence of its own). What is seen: the measured position stops where the
// edges stopped, under a force, and the run goes on to its end as for a device held still, then
// stops at zero on both channels. A detector needs what the lines do not carry
// (docs/drivers/gpio.md, "Several joints").
TEST_F(GpioXyKernelRun, SilencedEncodersCannotBeToldFromStillShafts) {
  const XyRun r = run(16.0, [](sim::gpio::GpioPeer& peer) {
    EXPECT_TRUE(peer.inject(sim::PeerFault::kStopAnswering));
  });
  std::cout << r.output;
  EXPECT_EQ(r.exit_code, 0) << "nothing on the wires says it: " << r.output;
  expect_both_stopped();
  // The hand went on pressing for seconds after the strike (at about a third of the way in):
  // heard, the penetration would have reached about 29.7 mm. It stayed where the edges stopped,
  // the same over the last two seconds.
  const double last_two = rest_penetration(r, 100);
  const double last_one = rest_penetration(r, 50);
  std::cout << "measured at the end " << last_one * 1e3 << " mm\n";
  EXPECT_GT(last_one, 0.0) << "in contact when silenced";
  EXPECT_LT(last_one, 0.6 * 0.0297) << "frozen where the edges stopped";
  EXPECT_DOUBLE_EQ(last_two, last_one) << "no edge since";
}

}  // namespace
}  // namespace hapticd::drivers::gpio
