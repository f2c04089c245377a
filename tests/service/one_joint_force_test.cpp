// A client's force on a device of one joint (servo_cf, docs/clients.md): added to the wall's
// through the one saturation once the direction check has armed the wall, saturated to
// safety.client_force_limit, gone when its client leaves, recorded and replayed bit for bit.
#include <gtest/gtest.h>

#include <chrono>
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

TEST(OneJointForce, ActsAfterTheCheckIsSaturatedAndGoesWithItsClient) {
  Daemon d({"--duration", "120", "--set", "loop.clock=realtime", "--set",
            "safety.client_force_limit=2"});
  ASSERT_TRUE(d.ready());
  d.wait_status([](const json& j) { return j["direction_check"]["armed"] == true; });
  {
    client::Connection c(d.socket(), 5000);
    const std::vector<double> two = {1.0, 0.0};
    EXPECT_THROW(c.servo_cf(two), client::Refused) << "two numbers for one joint";
    const std::vector<double> big = {-5.0};
    const json taken = c.servo_cf(big);
    EXPECT_EQ(taken["saturated"], true);
    EXPECT_EQ(taken["force"][0], -2.0);
    const std::vector<double> push = {-1.5};
    for (int i = 0; i < 30; ++i) {
      c.servo_cf(push);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }  // closed: its force goes at once
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ASSERT_EQ(d.ctl({"stop"}).exit_code, 0);
  EXPECT_EQ(d.wait().exit_code, 0);
  std::size_t pushed = 0, alone = 0;
  const telemetry::TickRecord* last = nullptr;
  const telemetry::LogContents log = telemetry::read_log(d.log());
  for (const telemetry::TickRecord& r : log.records) {
    if (r.marker != telemetry::kMarkerNone) continue;
    EXPECT_FALSE((r.flags & telemetry::kFlagProbe) && r.client_force[0] != 0.0)
        << "a client's force during the direction check, tick " << r.tick;
    last = &r;
    if (r.client_force[0] != -1.5) continue;
    ++pushed;
    // Where the wall pushes nothing, what was written is the client's force alone.
    if (r.force_computed == 0.0 && (r.flags & telemetry::kFlagPassivityDamped) == 0) {
      EXPECT_EQ(r.force_commanded, -1.5) << "tick " << r.tick;
      ++alone;
    }
  }
  EXPECT_GT(pushed, 200u);
  EXPECT_GT(alone, 0u);
  ASSERT_NE(last, nullptr);
  EXPECT_EQ(last->client_force[0], 0.0) << "a force left from a client that is gone";
  const ProcessResult replay = run_process({hapticd_binary(), "replay", d.log(), "--json"});
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_EQ(json::parse(replay.out)["reproduced"]["identical"], true) << replay.out;
}

}  // namespace
}  // namespace hapticd::testing
