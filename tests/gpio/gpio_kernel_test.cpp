// The GPIO driver on the kernel's own interfaces, in the kernel test machine: a gpio-sim chip
// (the encoder's lines, the direction and fault lines) and hapticd's PWM simulator (sysfs PWM),
// driven by libgpiod 1.6 on a Debian 12 root or 2.x on a Debian 13 one (tools/debian-root).
// The simulated encoder and motor driver on the far side is the driver's own peer on those
// endpoints (make_peer_on). Latency in an emulated guest measures qemu: nothing here times.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <climits>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "config/config_loader.h"
#include "drivers/gpio/gpio_device.h"
#include "drivers/gpio/gpiod_lines.h"
#include "drivers/gpio/sysfs_pwm.h"
#include "gpio_sim_chip.h"
#include "pwm_sim.h"
#include "sim/peers/gpio/gpio_peer.h"
#include "sim/peers/peer_runner.h"
#include "sysfs.h"
#include "wiring/registry.h"

namespace hapticd::drivers::gpio {
namespace {

using kernel_test::GpioSimChip;
using kernel_test::PwmApplied;
using kernel_test::PwmSim;
using namespace std::chrono_literals;

// What the emulated guest (qemu without KVM, on a loaded 2-core host) sustains. Its vCPUs
// stall for tens of milliseconds now and then (wake-ups over 100 ms late), and the kernel
// reads a gpio-sim line's level in the line's interrupt thread, which runs as late: two edges
// on one line closer than that reach the driver as one level. Hence:
//  - 50 Hz, the wall at 150 N/m: b_req = K T/2 + B = 150 x 0.01 + 0.2 = 1.7 <= 1.8 N s/m.
//    As in the CAN kernel runs, the loop tolerates the emulator's stalls: a streak of 50
//    overruns (1 s; a starved guest woke every tick over 20 ms late for 200 ms), and
//    safety.stale_fault_ticks 10 (200 ms: a sample carries its last edge's time, so a tick
//    woken 2 T late just after an edge would read as stale).
//  - max_edge_rate 25 edges/s (resolution 40 ms): the injected burst's edges are 10 ms apart
//    (four times the limit), the illegal pattern's steps 160 ms (its A/B pairs are written at
//    once: edges on two lines do not merge). A probe in the guest saw edges 10 ms apart on
//    one line merged rarely, 5 ms apart often.
//  - The peer spaces the plant's edges 2/max_edge_rate = 80 ms apart at least, so the press
//    must stay well below 12.5 edges/s, or the measured position slews behind the plant (the
//    settings before pressed at 150 edges/s: 8.6 mm for 5.5). A 0.5 mm encoder and the hand
//    ramped over 5 s from 1.75 mm outside to 10 mm inside: 4.7 edges/s, 3.1 in contact; the
//    chatter of the quantised wall across each count boundary is held to that spacing too.
//  - At rest the hand (300 N/m) and the wall balance at 6.67 mm, inside the count 6.5..7 mm:
//    the wall's 0.975 N holds the hand at 6.75 mm, mid-count, so it rests there.
const std::vector<std::string> kGuestSets = {
    "loop.rate_hz=50", "wall.stiffness=150", "device.gpio.counts_per_unit=2000",
    "device.sim.counts_per_unit=2000", "device.gpio.start_count=-4", "device.gpio.max_edge_rate=25",
    "loop.overrun_fault_streak=50", "safety.stale_fault_ticks=10",
    // The peer answers from its own timer in the emulated machine: up to 300 ms late. Its
    // encoder moves one count per 80 ms at most (above), so the check's push shows as a few
    // late counts, under what the check calls motion: the wall is armed unchecked (it says so),
    // and the runaway guard still watches. The check on a GPIO device is proven against the
    // loopback peer, whose edges are not spaced out (tests/drivers, tests/service).
    "safety.direction_check.max_latency_ms=300", "safety.direction_check.on_no_motion=run",
    // Mid-count, so the plant at rest (numerically still only to 1e-18) does not dither
    // across a count boundary; count -4 has the lines at 00, where gpio-sim leaves them.
    "device.sim.initial_position=-0.00175", "device.sim.operator.setpoint.rest=-0.00175",
    // The hand presses 2 s after the plant starts (before hapticd enables: the direction check
    // pushes a device at rest and sees it move, ~0.5 s at 50 Hz in the emulated machine).
    "device.sim.operator.setpoint.start=2", "device.sim.operator.setpoint.ramp=5",
    "device.sim.operator.setpoint.hold=2"};

// N of the simulator's /sys/class/pwm/pwmchipN.
unsigned pwm_chip_number(const PwmSim& pwm) {
  const std::string p = pwm.chip_path();
  return static_cast<unsigned>(std::stoul(p.substr(p.rfind("pwmchip") + 7)));
}

struct Machine {
  GpioSimChip chip{5, "hapticd-gpio-sim"};
  PwmSim pwm;
  std::string chip_dir() const {
    char buf[PATH_MAX];
    const std::string link = "/sys/bus/gpio/devices/" + chip.chip_name();
    if (realpath(link.c_str(), buf) == nullptr) throw std::runtime_error("no " + link);
    return buf;
  }
  std::vector<std::string> sets() const {
    std::vector<std::string> s = kGuestSets;
    s.push_back("device.gpio.chip=" + chip.label());  // found by its label
    s.push_back("device.gpio.pwm.chip=" + std::to_string(pwm_chip_number(pwm)));
    return s;
  }
  std::string endpoint() const {
    return chip_dir() + ",/sys/devices/platform/hapticd-pwm-sim/channel0";
  }
};

config::Config load(const std::vector<std::string>& sets) {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/gpio.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::vector<config::Override> o;
  for (const auto& s : sets) o.push_back(config::parse_override(s));
  return config::load_config_text(text.str(), "config/gpio.yaml", o, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

TEST(GpioKernel, DeviceOnGpioSimAndThePwmSimulator) {
  Machine m;
  RecordProperty("libgpiod", GpiodLines::api());
  std::cout << "driver built against " << GpiodLines::api() << "\n";
  const config::Config cfg = load(m.sets());
  m.chip.set_pull(3, true);  // nFAULT released
  auto device = wiring::find_driver("gpio").make_device(cfg);
  device->configure();
  EXPECT_NE(device->info().description.find("hapticd-gpio-sim"), std::string::npos)
      << device->info().description;
  // Issue 22: enabled at configure, at duty 0 (a disabled channel's output is undefined).
  EXPECT_TRUE(m.pwm.applied(0).enabled) << "configured with the channel on, at duty 0";
  EXPECT_EQ(m.pwm.applied(0).duty_cycle_ns, 0u);
  device->enable();
  PositionSample s;
  ASSERT_EQ(device->read(s), IoStatus::kOk);
  EXPECT_NE(s.status & kStatusNoEdge, 0u) << "nothing moved: the read time, marked";
  EXPECT_DOUBLE_EQ(s.position, -4 / 2000.0);
  ASSERT_EQ(device->write(5.0), IoStatus::kOk);
  PwmApplied a = m.pwm.applied(0);
  EXPECT_TRUE(a.enabled);
  EXPECT_EQ(a.period_ns, 50'000u);
  EXPECT_EQ(a.duty_cycle_ns, 25'000u) << "5 N of 10 N: half the period";
  EXPECT_TRUE(m.chip.value(2)) << "positive force: direction high";
  ASSERT_EQ(device->write(-2.0), IoStatus::kOk);
  EXPECT_FALSE(m.chip.value(2));
  EXPECT_EQ(m.pwm.applied(0).duty_cycle_ns, 10'000u);
  // One count forward: A rises (00 -> 10), timestamped by the kernel.
  timespec before{};
  clock_gettime(CLOCK_MONOTONIC, &before);
  m.chip.set_pull(0, true);
  std::this_thread::sleep_for(20ms);
  ASSERT_EQ(device->read(s), IoStatus::kOk);
  EXPECT_DOUBLE_EQ(s.position, -3 / 2000.0);
  EXPECT_EQ(s.status & kStatusNoEdge, 0u);
  EXPECT_GE(s.time_ns, before.tv_sec * 1'000'000'000LL + before.tv_nsec) << "the edge's time";
  device->emergency_stop();  // what the crash handler does: zero on the open descriptor
  EXPECT_EQ(m.pwm.applied(0).duty_cycle_ns, 0u);
  // The motor driver pulls nFAULT low: a device fault, zero duty at once.
  ASSERT_EQ(device->write(3.0), IoStatus::kOk);
  m.chip.set_pull(3, false);
  std::this_thread::sleep_for(20ms);
  EXPECT_EQ(device->read(s), IoStatus::kDeviceFault);
  EXPECT_NE(device->describe_fault().find("fault line"), std::string::npos);
  EXPECT_EQ(m.pwm.applied(0).duty_cycle_ns, 0u);
  device->close();
  EXPECT_TRUE(m.pwm.applied(0).enabled) << "closed as every stop: duty 0, channel on";
  EXPECT_EQ(m.pwm.applied(0).duty_cycle_ns, 0u);
  // Configured again: the channel is still exported (the export answers EBUSY), which is fine;
  // the fault line still active refuses it.
  EXPECT_THROW(device->configure(), DeviceError);
  m.chip.set_pull(3, true);
  device->configure();
  device->enable();
  // Unplugged mid-run: the chip goes away under the open line request.
  kernel_test::write_text("/sys/kernel/config/gpio-sim/hapticd/live", "0");
  for (int tick = 0; tick < 10 && device->state() == DeviceState::kActive; ++tick) {
    if (device->read(s) == IoStatus::kOk) device->write(1.0);  // the direction line's ioctl
  }
  EXPECT_EQ(device->state(), DeviceState::kFaulted) << "an unplugged chip must be noticed";
  EXPECT_EQ(device->fault().fault_class, FaultClass::kTransport) << device->describe_fault();
  std::cout << "unplugged: " << device->describe_fault() << "\n";
  EXPECT_EQ(m.pwm.applied(0).duty_cycle_ns, 0u);
  device->close();
}

// Issue 22, on the real PWM core: a channel some earlier run or tool left enabled and driving,
// at a longer period than its duty and the other polarity, is taken over in an order the core
// accepts (duty 0 first, the polarity changed only while the channel is at duty 0) and ends
// enabled at duty 0; a stop and the close leave it there, the one state whose output Linux
// defines (Documentation/driver-api/pwm.rst).
TEST(GpioKernel, SysfsPwmTakesOverAChannelLeftDrivingAndStopsEnabledAtZero) {
  PwmSim sim;
  ASSERT_GE(sim.npwm(), 2u);
  const std::string dir = sim.chip_path() + "/pwm1";
  if (!kernel_test::path_exists(dir)) kernel_test::write_text(sim.chip_path() + "/export", "1");
  struct Unexport {  // however the test ends: the PWM simulator's own test exports it again
    std::string chip;
    ~Unexport() {
      try {
        kernel_test::write_text(chip + "/unexport", "1");
      } catch (const kernel_test::KernelFacilityError&) {
      }
    }
  } unexport{sim.chip_path()};
  kernel_test::wait_until([&] { return kernel_test::path_exists(dir + "/enable"); }, 5000ms,
                          dir + " after export");
  kernel_test::write_text(dir + "/period", "1000000");
  kernel_test::write_text(dir + "/duty_cycle", "600000");
  kernel_test::write_text(dir + "/polarity", "normal");
  kernel_test::write_text(dir + "/enable", "1");
  ASSERT_TRUE(sim.applied(1).enabled);
  ASSERT_EQ(sim.applied(1).duty_cycle_ns, 600'000u) << "left driving";

  SysfsPwm pwm;
  PwmChannel ch;
  ch.chip = pwm_chip_number(sim);
  ch.channel = 1;
  ch.period_ns = 50'000;  // below the duty left behind
  ch.inversed = true;
  ASSERT_NO_THROW(pwm.open(ch));
  PwmApplied a = sim.applied(1);
  EXPECT_TRUE(a.enabled);
  EXPECT_EQ(a.duty_cycle_ns, 0u);
  EXPECT_EQ(a.period_ns, 50'000u);
  EXPECT_TRUE(a.inversed);
  ASSERT_EQ(pwm.write(20'000), 0);
  EXPECT_EQ(sim.applied(1).duty_cycle_ns, 20'000u);
  ASSERT_EQ(pwm.write(0), 0);
  pwm.close();
  a = sim.applied(1);
  EXPECT_TRUE(a.enabled) << "never disabled by a stop or the close";
  EXPECT_EQ(a.duty_cycle_ns, 0u);
}

// `hapticd run` against the peer on gpio-sim and the PWM simulator.
struct RunResult {
  int exit_code = -1;
  nlohmann::json summary;
  std::string output;
};

// hapticd takes seconds to start in an emulated guest, more on a loaded host: the peer, and
// with it the plant's clock and the hand's press, starts (start_peer) once hapticd has
// configured (the PWM channel is enabled at duty 0 from configure on) and passed its gate,
// before it enables output: the plant moves when the direction check pushes it, as a real one
// does. At the start count the lines are at 00, where gpio-sim has them: no edge then.
RunResult run_hapticd(const Machine& m, double duration_s, const std::vector<std::string>& extra,
                      const std::function<sim::gpio::GpioPeer&()>& start_peer,
                      std::optional<sim::gpio::WireFault> fault) {
  const std::string dir = "/tmp/hapticd-gpio-kt-" + std::to_string(getpid());
  mkdir(dir.c_str(), 0755);
  std::vector<std::string> args = {HAPTICD_BINARY,   "run",
                                   "--config",       HAPTICD_SOURCE_DIR "/config/gpio.yaml",
                                   "--duration",     std::to_string(duration_s),
                                   "--summary-json", dir + "/summary.json"};
  for (const auto& s : m.sets()) args.insert(args.end(), {"--set", s});
  for (const auto& s : extra) args.insert(args.end(), {"--set", s});
  const std::string out = dir + "/output.txt";
  unlink(out.c_str());  // the previous run's log says "output enabled" too
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
  const auto until = std::chrono::steady_clock::now() + 60s;
  const auto running = [&] {
    return std::chrono::steady_clock::now() < until &&
           !(exited = waitpid(pid, &status, WNOHANG) == pid);
  };
  const auto output = [&] {  // hapticd's log, flushed line by line
    std::ifstream log(out);
    std::stringstream text;
    text << log.rdbuf();
    return text.str();
  };
  const auto logged = [&](const char* words) { return output().find(words) != std::string::npos; };
  while (running() && !logged("gate: pass")) std::this_thread::sleep_for(5ms);
  if (!exited) {
    sim::gpio::GpioPeer& peer = start_peer();
    if (fault) {
      // Once the wall pushes (armed by the direction check, a duty applied and the device in
      // contact), strike.
      while (!logged("direction check:") && running()) std::this_thread::sleep_for(5ms);
      while (peer.applied_force() >= -0.5 && running()) std::this_thread::sleep_for(5ms);
      EXPECT_LT(peer.applied_force(), -0.5) << "the wall never pushed";
      EXPECT_TRUE(peer.inject_wire(*fault));
    }
  }
  if (!exited) waitpid(pid, &status, 0);
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.output = output();
  std::ifstream js(dir + "/summary.json");
  if (js) r.summary = nlohmann::json::parse(js, nullptr, false);
  return r;
}

class GpioKernelRun : public testing::Test {
 protected:
  void SetUp() override {
    cfg_ = std::make_unique<config::Config>(load(m_.sets()));
    m_.chip.set_pull(3, true);  // nFAULT released: hapticd configures before the peer is there
  }
  void TearDown() override {
    if (!runner_) return;
    runner_->stop();
    EXPECT_EQ(runner_->error(), "");
  }
  RunResult run(double duration_s, std::optional<sim::gpio::WireFault> fault) {
    return run_hapticd(
        m_, duration_s, {},
        [this]() -> sim::gpio::GpioPeer& {
          auto peer = wiring::find_driver("gpio").peer.make_peer_on(*cfg_, m_.endpoint());
          peer_.reset(dynamic_cast<sim::gpio::GpioPeer*>(peer.release()));
          runner_ = std::make_unique<sim::PeerRunner>(*peer_, 50);
          return *peer_;
        },
        fault);
  }
  Machine m_;
  std::unique_ptr<config::Config> cfg_;
  std::unique_ptr<sim::gpio::GpioPeer> peer_;
  std::unique_ptr<sim::PeerRunner> runner_;
};

TEST_F(GpioKernelRun, RendersTheWallAt50HzNoFault) {
  const RunResult r = run(10.0, std::nullopt);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(r.summary.is_object()) << r.output;
  EXPECT_EQ(r.summary["faults"].size(), 0u) << r.output;
  EXPECT_GT(r.summary["counters"]["loop"]["contact_ticks"].get<double>(), 100.0) << r.output;
  // Hand 300 N/m pressing 10 mm in against 150 N/m: p = 300 x 10 / 450 = 6.67 mm at rest.
  EXPECT_NEAR(r.summary["max_penetration"].get<double>(), 300 * 10e-3 / 450, 1e-3) << r.output;
  std::cout << r.output;
  EXPECT_EQ(m_.pwm.applied(0).duty_cycle_ns, 0u) << "zero when the run ended";
}

TEST_F(GpioKernelRun, EdgeBurstFasterThanTheLimitFaultsWithZeroDuty) {
  const RunResult r = run(20.0, sim::gpio::WireFault::kEdgeBurst);
  std::cout << r.output;  // the fault's message, for the log
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("faster than device.gpio.max_edge_rate"), std::string::npos) << r.output;
  EXPECT_EQ(m_.pwm.applied(0).duty_cycle_ns, 0u);
  EXPECT_TRUE(m_.pwm.applied(0).enabled) << "stopped at duty 0, the channel on";
}

TEST_F(GpioKernelRun, IllegalTransitionPatternFaultsWithZeroDuty) {
  const RunResult r = run(20.0, sim::gpio::WireFault::kIllegalPattern);
  std::cout << r.output;  // the fault's message, for the log
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("illegal transitions"), std::string::npos) << r.output;
  EXPECT_EQ(m_.pwm.applied(0).duty_cycle_ns, 0u);
  EXPECT_TRUE(m_.pwm.applied(0).enabled) << "stopped at duty 0, the channel on";
}

}  // namespace
}  // namespace hapticd::drivers::gpio
