// The state stream on the running daemon (docs/clients.md, the state stream): every N-th tick
// as a line of its own, unasked, beside the answers to the client's requests; a client that
// does not read is not waited for and is told what it missed; the C++ client and hapticctl
// read it.
#include <gtest/gtest.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

#include "client/connection.h"
#include "daemon.h"
#include "process.h"

namespace hapticd::testing {
namespace {

using nlohmann::json;

Daemon scene_daemon() {
  return Daemon({"--config", source_dir() + "/config/sim-delta-scene.yaml", "--duration", "120"});
}

TEST(StateStreamClients, EveryTenthTickArrivesBesideTheAnswersWithNoneMissed) {
  Daemon d = scene_daemon();
  ASSERT_TRUE(d.ready());
  RawClient c(d.socket());
  ASSERT_TRUE(c.send(R"({"v":1,"id":"s","cmd":"stream","every":10})"
                     "\n"));
  const json started = json::parse(c.line(), nullptr, false);
  ASSERT_EQ(started["ok"], true) << started.dump();
  EXPECT_EQ(started["stream"]["rate_hz"], 100.0);
  std::int64_t last = -1;
  int samples = 0, answers = 0;
  for (int i = 0; i < 150; ++i) {
    if (i == 50) {
      ASSERT_TRUE(c.send(R"({"v":1,"id":"q","cmd":"status"})"
                         "\n"));
    }
    const json l = json::parse(c.line(5000), nullptr, false);
    ASSERT_TRUE(l.is_object()) << "line " << i;
    if (l.contains("ok")) {  // the answer to the status request, whole among the samples
      EXPECT_EQ(l["id"], "q");
      EXPECT_EQ(l["status"]["state"], "running");
      ++answers;
      continue;
    }
    const json& s = l["stream"];
    const auto tick = s["tick"].get<std::int64_t>();
    if (last >= 0) {
      EXPECT_EQ(tick - last, 10) << "every tenth tick, none skipped";
    }
    last = tick;
    EXPECT_EQ(s["missed"], 0);
    EXPECT_EQ(s["measured_cp"].size(), 3u);
    ++samples;
  }
  EXPECT_EQ(answers, 1);
  EXPECT_EQ(samples, 149);
  ASSERT_TRUE(c.send(R"({"v":1,"cmd":"stream","every":0})"
                     "\n"));
  json stopped;
  do {
    stopped = json::parse(c.line(5000), nullptr, false);
  } while (stopped.is_object() && !stopped.contains("ok"));
  EXPECT_EQ(stopped["stream"]["every"], 0);
  EXPECT_GE(stopped["stream"]["sent"].get<int>(), 149);
  EXPECT_EQ(c.line(300), "") << "no sample after the stream stopped";
}

// A client streaming every tick that reads nothing for three seconds: the daemon goes on (the
// others are answered, the loop runs), queues no more than its backlog, and a line the client
// reads after it says how many it missed.
TEST(StateStreamClients, AReaderThatStopsReadingIsNotWaitedForAndIsToldWhatItMissed) {
  Daemon d = scene_daemon();
  ASSERT_TRUE(d.ready());
  RawClient c(d.socket());
  ASSERT_TRUE(c.send(R"({"v":1,"cmd":"stream","every":1})"
                     "\n"));
  ASSERT_EQ(json::parse(c.line(), nullptr, false)["ok"], true);
  const auto t0 = d.status()["tick"].get<std::uint64_t>();
  std::this_thread::sleep_for(std::chrono::seconds(3));
  const json s = d.status();  // another client, answered meanwhile
  // Its pace is a benchmark's (BENCHMARKS.md); here, that it ran on.
  EXPECT_GT(s["tick"].get<std::uint64_t>(), t0 + 1000) << "the loop ran on";
  std::uint64_t missed = 0;
  for (int i = 0; i < 20000 && missed == 0; ++i) {
    const json l = json::parse(c.line(5000), nullptr, false);
    ASSERT_TRUE(l.is_object());
    missed = l["stream"]["missed"].get<std::uint64_t>();
  }
  EXPECT_GT(missed, 0u) << "what it could not be sent is counted";
}

TEST(StateStreamClients, TheCppClientAndHapticctlReadTheStream) {
  Daemon d = scene_daemon();
  ASSERT_TRUE(d.ready());
  {
    client::Connection c(d.socket(), 5000);
    EXPECT_EQ(c.stream(5)["every"], 5);
    EXPECT_EQ(c.status()["state"], "running") << "samples before an answer are set aside";
    std::optional<json> first = c.next_sample(2000);
    ASSERT_TRUE(first.has_value());
    for (int i = 0; i < 20; ++i) {
      const std::optional<json> next = c.next_sample(2000);
      ASSERT_TRUE(next.has_value());
      EXPECT_EQ((*next)["tick"].get<std::int64_t>() - (*first)["tick"].get<std::int64_t>(), 5);
      first = next;
    }
  }
  const ProcessResult r = run_process(
      {hapticctl_binary(), "--socket", d.socket(), "stream", "--every", "100", "--count", "3"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream out(r.out);
  int n = 0;
  for (std::string l; std::getline(out, l); ++n) {
    EXPECT_TRUE(json::parse(l, nullptr, false).contains("measured_cp")) << l;
  }
  EXPECT_EQ(n, 3);
}

}  // namespace
}  // namespace hapticd::testing
