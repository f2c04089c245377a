// An attractor added by a client (docs/kinematics.md, attractors; docs/clients.md): gated like a
// wall, it pulls the simulated delta of config/sim-delta-scene.yaml (a hand resting on a floor)
// to where its pull, the hand's and the floor's balance; it goes with the client that added it,
// and the device settles back on the floor; one too stiff for the device's weakest direction is
// refused with the gate's numbers; one added to be kept outlives its client. The log replays bit
// for bit.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "client/connection.h"

#include "daemon.h"
#include "process.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

json add_over(RawClient& c, const std::string& wall) {
  EXPECT_TRUE(c.send(R"({"v":1,"cmd":"scene","op":"add","wall":)" + wall + "}\n"));
  return json::parse(c.line(), nullptr, false);
}

// Where the effector is once `ticks` more ticks have gone by after `since`.
json settled(const Daemon& d, std::uint64_t since, std::uint64_t ticks = 1500) {
  return d.wait_status(
      [&](const json& j) { return j["tick"].get<std::uint64_t>() > since + ticks; });
}

TEST(SceneAttractor, PullsTheDeviceToWhereItBalancesTheHandAndGoesWithItsClient) {
  Daemon d({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "120"});
  ASSERT_TRUE(d.ready());
  // The hand (200 N/m to 20 mm below the start) on the floor (500 N/m at z = 0.105): at rest at
  // z = (200 0.09 + 500 0.105) / 700.
  json s = settled(d, 0);
  EXPECT_NEAR(s["task_position"][2].get<double>(), 70.5 / 700.0, 3e-4);
  EXPECT_NEAR(s["task_position"][0].get<double>(), 0.0, 3e-4);
  {
    RawClient c(d.socket());
    // Too stiff for lambda_min(B_c) (0.45 N s/m on this delta): refused, the numbers named.
    const json stiff =
        add_over(c, R"({"kind": "attractor", "point": [0, 0, 0.11], "stiffness": 5000})");
    EXPECT_EQ(stiff["code"], 3) << stiff.dump();
    EXPECT_NE(stiff["error"].get<std::string>().find("lambda_min(B_c)"), std::string::npos)
        << stiff.dump();
    // 100 N/m to (10, 0, 110) mm: x = 100 0.01 / 300, z = (18 + 52.5 + 11) / 800.
    const json a =
        add_over(c, R"({"kind": "attractor", "point": [0.01, 0, 0.11], "stiffness": 100,)"
                    R"( "damping": 0.05})");
    ASSERT_EQ(a["ok"], true) << a.dump();
    EXPECT_EQ(a["scene"]["index"], 1);
    s = settled(d, a["scene"]["applied_at_tick"].get<std::uint64_t>());
    EXPECT_NEAR(s["task_position"][0].get<double>(), 0.01 / 3.0, 3e-4) << s.dump();
    EXPECT_NEAR(s["task_position"][1].get<double>(), 0.0, 3e-4);
    EXPECT_NEAR(s["task_position"][2].get<double>(), 81.5 / 800.0, 3e-4);
    EXPECT_EQ(s["walls"][1]["kind"], "attractor");
    EXPECT_TRUE(s["walls"][1]["normal"].is_null());
  }
  // Its client gone, the attractor goes, and the device settles back on the floor.
  s = d.wait_status([](const json& j) { return j["walls"].size() == 1; });
  s = settled(d, s["tick"].get<std::uint64_t>());
  EXPECT_NEAR(s["task_position"][0].get<double>(), 0.0, 3e-4);
  EXPECT_NEAR(s["task_position"][2].get<double>(), 70.5 / 700.0, 3e-4);
  {
    // Through the C++ client, kept: its max_force in the status, and it outlives the client.
    client::Connection c(d.socket(), 5000);
    const std::vector<double> point = {0.0, 0.0, 0.1};
    EXPECT_EQ(c.add_attractor(point, 100.0, 0.05, 1.5, true), 1u);
  }
  s = d.status();
  ASSERT_EQ(s["walls"].size(), 2u) << "a kept attractor went with its client";
  EXPECT_EQ(s["walls"][1]["max_force"], 1.5);
  EXPECT_EQ(s["walls"][1]["kind"], "attractor");
  ASSERT_EQ(d.ctl({"stop"}).exit_code, 0);
  EXPECT_EQ(d.wait().exit_code, 0);
  const ProcessResult replay = run_process({hapticd_binary(), "replay", d.log(), "--json"});
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_EQ(json::parse(replay.out)["reproduced"]["identical"], true) << replay.out;
}

}  // namespace
}  // namespace hapticd::testing
