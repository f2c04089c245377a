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

#include "daemon.h"
#include "process.h"

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

}  // namespace
}  // namespace hapticd::testing
