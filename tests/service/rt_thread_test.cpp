// The RT thread's start gate (service/run_threads.h): the thread is made, scheduled and
// configured before output is enabled, and its loop ticks only once start() opens the gate,
// so a drive's watchdog sees commands within a period of the enable. A thread stopped or
// destroyed before start() never runs the loop: no tick, no command.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "config/config_loader.h"
#include "control/controller.h"
#include "loop/servo_loop.h"
#include "service/run/run_threads.h"
#include "sim/sim_device.h"

namespace hapticd::service {
namespace {

struct ThreadRig {
  ThreadRig()
      : device(cfg.device, cfg.loop.sample_period_s()), law(control::make_control_law(cfg)) {
    device.configure();
    device.enable();
  }
  loop::LoopOptions options() const {
    loop::LoopOptions o;
    o.sample.realtime = false;
    return o;
  }
  config::Config cfg = config::load_embedded_default({});
  sim::SimDevice device;
  control::Controller law;
  loop::ServoLoop loop{device, law, nullptr, options()};
  loop::RtStatus rt;
};

bool eventually(const auto& condition) {
  for (int i = 0; i < 20000 && !condition(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return condition();
}

TEST(RtThread, TheLoopWaitsAtTheGateUntilStartThenTicks) {
  ThreadRig rig;
  RtThread thread(rig.loop, 1, -1, false, rig.rt);
  ASSERT_EQ(thread.wait_ready(), "");
  // A loop that ran early would have ticked thousands of times (freerun) by now.
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(rig.loop.ticks_done(), 0u) << "no tick before start()";
  EXPECT_FALSE(thread.finished());
  thread.start();
  thread.wait_running();  // what READY=1 waits for
  EXPECT_GT(rig.loop.ticks_done(), 0u) << "wait_running() returns once the loop has ticked";
  EXPECT_TRUE(eventually([&] { return rig.loop.ticks_done() > 100; }));
  thread.request_stop();
  EXPECT_GT(thread.join().ticks, 100u);
  EXPECT_TRUE(thread.finished());
}

TEST(RtThread, AStopBeforeStartMeansTheLoopNeverRuns) {
  ThreadRig rig;
  RtThread thread(rig.loop, 1, -1, false, rig.rt);
  ASSERT_EQ(thread.wait_ready(), "");
  thread.request_stop();
  EXPECT_TRUE(eventually([&] { return thread.finished(); })) << "the supervisor learns of it";
  thread.start();         // too late: the gate was closed for good
  thread.wait_running();  // returns: the loop will never tick
  EXPECT_EQ(thread.join().ticks, 0u);
  EXPECT_EQ(rig.loop.ticks_done(), 0u);
}

TEST(RtThread, ADestroyedUnstartedThreadJoinsWithoutRunningTheLoop) {
  ThreadRig rig;
  {
    RtThread thread(rig.loop, 1, -1, false, rig.rt);
    ASSERT_EQ(thread.wait_ready(), "");
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }  // as when enabling the device threw
  EXPECT_EQ(rig.loop.ticks_done(), 0u);
}

}  // namespace
}  // namespace hapticd::service
