// What a client leaving means (docs/clients.md): the walls a client added belong to its
// connection and go at the next tick boundary when it ends - closed, killed - with no new gate;
// a wall added to be kept ("keep", or safety.client_walls_on_leave: keep) stays. The log
// replays the removal bit for bit.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "client/connection.h"
#include "daemon.h"
#include "process.h"
#include "telemetry/log_reader.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

// A wall beside the floor of config/sim-delta-scene.yaml, out of the hand's way.
constexpr const char* kSideWall =
    R"({"point": [0.03, 0, 0.1], "normal": [1, 0, 0], "stiffness": 400})";

std::size_t walls(const Daemon& d) { return d.status()["walls"].size(); }

// Polls until the daemon has `n` walls (about 5 s at most); whether it came to have them.
bool comes_to(const Daemon& d, std::size_t n) {
  for (int i = 0; i < 100; ++i) {
    if (walls(d) == n) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

json add(RawClient& c, const std::string& extra = "") {
  EXPECT_TRUE(c.send(R"({"v":1,"cmd":"scene","op":"add","wall":)" + std::string(kSideWall) + extra +
                     "}\n"));
  return json::parse(c.line(), nullptr, false);
}

TEST(SceneClients, AClosedClientsWallGoesAtOnceAndAKeptOneStays) {
  Daemon d({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "120"});
  ASSERT_TRUE(d.ready());
  {
    RawClient c(d.socket());
    const json a = add(c);
    ASSERT_EQ(a["ok"], true) << a.dump();
    EXPECT_EQ(a["scene"]["index"], 1);
    EXPECT_EQ(walls(d), 2u);
  }
  EXPECT_TRUE(comes_to(d, 1)) << "the closed client's wall stayed";
  {
    RawClient c(d.socket());
    ASSERT_EQ(add(c, R"(, "keep": true)")["ok"], true);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(walls(d), 2u) << "a wall added with keep went with its client";
  RawClient bad(d.socket());
  ASSERT_TRUE(bad.send(R"({"v":1,"cmd":"scene","op":"remove","index":1,"keep":true})"
                       "\n"));
  const json refused = json::parse(bad.line(), nullptr, false);
  EXPECT_EQ(refused["code"], 2) << refused.dump();
  EXPECT_NE(refused["error"].get<std::string>().find("\"keep\" is for add alone"),
            std::string::npos);
  ASSERT_EQ(d.ctl({"stop"}).exit_code, 0);
  EXPECT_EQ(d.wait().exit_code, 0);
  const ProcessResult replay = run_process({hapticd_binary(), "replay", d.log(), "--json"});
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_EQ(json::parse(replay.out)["reproduced"]["identical"], true) << replay.out;
}

// A client killed (SIGKILL: no goodbye, the kernel closes its socket) loses its wall too.
TEST(SceneClients, AKilledClientsWallGoes) {
  Daemon d({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "120"});
  ASSERT_TRUE(d.ready());
  const std::string script =
      "import sys, time, hapticd\n"
      "c = hapticd.Client(sys.argv[1])\n"
      "c.add_wall([0.03, 0, 0.1], [1, 0, 0], 400)\n"
      "print('added', flush=True)\n"
      "time.sleep(600)\n";
  BackgroundProcess client({"/usr/bin/python3", "-c", script, d.socket()},
                           {"PYTHONPATH=" + source_dir() + "/python"});
  ASSERT_TRUE(comes_to(d, 2)) << "the client's wall never came";
  client.signal(SIGKILL);
  client.wait();
  EXPECT_TRUE(comes_to(d, 1)) << "the killed client's wall stayed";
}

TEST(SceneClients, KeptByConfigurationTheyStayAndBecomeTheConfigurations) {
  Daemon d({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "120", "--set",
            "safety.client_walls_on_leave=keep"});
  ASSERT_TRUE(d.ready());
  {
    RawClient c(d.socket());
    ASSERT_EQ(add(c)["ok"], true);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(walls(d), 2u);
  {
    RawClient c(d.socket());
    ASSERT_EQ(add(c, R"(, "keep": false)")["ok"], true);  // this one asked to go
  }
  EXPECT_TRUE(comes_to(d, 2));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(walls(d), 2u);
}

// What servo_cf refuses, by name: no force configured (on a device of one joint too), a force
// that is not finite.
TEST(SceneClients, ACommandedForceIsRefusedWhereItMayNotBe) {
  Daemon d({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "120"});
  ASSERT_TRUE(d.ready());
  RawClient c(d.socket());
  const auto ask = [&](const std::string& force) {
    EXPECT_TRUE(c.send(R"({"v":1,"cmd":"servo_cf","force":)" + force + "}\n"));
    return json::parse(c.line(), nullptr, false);
  };
  json a = ask("[0, 0, 1]");
  EXPECT_EQ(a["code"], 2);
  EXPECT_NE(a["error"].get<std::string>().find("safety.client_force_limit is 0"), std::string::npos)
      << a.dump();
  a = ask(R"([0, 0, "inf"])");
  EXPECT_EQ(a["code"], 2);
  EXPECT_NE(a["error"].get<std::string>().find("\"force\"[2]: must be a finite number (N)"),
            std::string::npos)
      << a.dump();
  Daemon one({"--duration", "120", "--set", "loop.clock=realtime"});
  ASSERT_TRUE(one.ready());
  RawClient c1(one.socket());
  ASSERT_TRUE(c1.send(R"({"v":1,"cmd":"servo_cf","force":[1]})"
                      "\n"));
  a = json::parse(c1.line(), nullptr, false);
  EXPECT_EQ(a["code"], 2);
  EXPECT_NE(a["error"].get<std::string>().find("safety.client_force_limit is 0"), std::string::npos)
      << a.dump();
}

TEST(SceneClients, ACommandedForceOfTheWrongSizeIsRefusedAndATooLargeOneSaturated) {
  Daemon d({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "120", "--set",
            "safety.client_force_limit=2"});
  ASSERT_TRUE(d.ready());
  client::Connection c(d.socket(), 5000);
  const std::vector<double> two = {0.0, 1.0};
  try {
    c.servo_cf(two);
    ADD_FAILURE() << "a force of two numbers was taken by a device of three axes";
  } catch (const client::Refused& e) {
    EXPECT_EQ(e.code(), 2);
    EXPECT_NE(std::string(e.what()).find("the device has 3 task axes, the force 2 numbers"),
              std::string::npos)
        << e.what();
  }
  const std::vector<double> big = {0.0, 3.0, 4.0};
  const json taken = c.servo_cf(big);
  EXPECT_EQ(taken["saturated"], true);
  EXPECT_NEAR(taken["force"][1].get<double>(), 1.2, 1e-12);  // 5 N along (0, 0.6, 0.8) -> 2 N
  EXPECT_NEAR(taken["force"][2].get<double>(), 1.6, 1e-12);
}

// A client pushing up on the delta at 100 Hz (servo_cf), killed: its force is gone within a few
// ticks (its leaving, not the hold's 100 ms); another, stopped (SIGSTOP: connected, silent):
// its force holds, then fades to zero over the 50 ms ramp. The log replays both bit for bit.
TEST(SceneClients, AKilledClientsForceGoesAtOnceAndASilentOnesFadesOverTheRamp) {
  Daemon d({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "120", "--set",
            "safety.client_force_limit=2"});
  ASSERT_TRUE(d.ready());
  const std::string pusher =
      "import sys, time, hapticd\n"
      "c = hapticd.Client(sys.argv[1])\n"
      "while True:\n"
      "    c.servo_cf([0, 0, 1.0])\n"
      "    time.sleep(0.01)\n";
  const std::vector<std::string> env = {"PYTHONPATH=" + source_dir() + "/python"};
  client::Connection c(d.socket(), 5000);
  const client::StateReader state = c.state();
  const auto now_tick = [&] {
    client::StateSample s;
    EXPECT_TRUE(state.latest(s));
    return s.tick;
  };
  std::uint64_t killed_at = 0, stopped_at = 0;
  {
    BackgroundProcess p({"/usr/bin/python3", "-c", pusher, d.socket()}, env);
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    killed_at = now_tick();
    p.signal(SIGKILL);
    p.wait();
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  {
    BackgroundProcess p({"/usr/bin/python3", "-c", pusher, d.socket()}, env);
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    stopped_at = now_tick();
    p.signal(SIGSTOP);
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    p.signal(SIGKILL);
    p.wait();
  }
  ASSERT_EQ(d.ctl({"stop"}).exit_code, 0);
  EXPECT_EQ(d.wait().exit_code, 0);
  std::vector<telemetry::TickRecord> ticks;
  for (const telemetry::TickRecord& r : telemetry::read_log(d.log()).records) {
    if (r.marker == telemetry::kMarkerNone) ticks.push_back(r);
  }
  const auto first_zero_from = [&](std::uint64_t tick) -> std::size_t {
    for (std::size_t i = 0; i < ticks.size(); ++i) {
      if (ticks[i].tick >= tick && ticks[i].client_force[2] == 0.0) return i;
    }
    return ticks.size();
  };
  const std::size_t gone = first_zero_from(killed_at);
  ASSERT_LT(gone, ticks.size());
  EXPECT_EQ(ticks[gone - 1].client_force[2], 1.0) << "it pushed until it was killed";
  EXPECT_LT(ticks[gone].tick - killed_at, 50u) << "the killed client's force stayed";
  const std::size_t faded = first_zero_from(stopped_at);
  ASSERT_LT(faded, ticks.size());
  std::size_t full = faded;
  while (full > 0 && ticks[full - 1].client_force[2] < 1.0) --full;
  // From the last tick at full force down the ramp, each tick less than the last, to the first
  // at zero: 50 ms of the ticks' wake times apart, and no more than the ramp and the two periods
  // it started and ended in (a loaded machine skips periods: ticks are not time).
  const auto woke = [&](std::size_t i) {
    return static_cast<double>(ticks[i].scheduled_ns + ticks[i].wake_latency_ns) * 1e-6;
  };
  const double ramp = woke(faded) - woke(full - 1);
  EXPECT_GE(ramp, 50.0);
  EXPECT_LE(ramp, 50.0 + (woke(full) - woke(full - 1)) + (woke(faded) - woke(faded - 1)));
  for (std::size_t i = full; i < faded; ++i) {
    EXPECT_LT(ticks[i].client_force[2], ticks[i - 1].client_force[2]) << "tick " << ticks[i].tick;
  }
  const ProcessResult replay = run_process({hapticd_binary(), "replay", d.log(), "--json"});
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_EQ(json::parse(replay.out)["reproduced"]["identical"], true) << replay.out;
}

}  // namespace
}  // namespace hapticd::testing
