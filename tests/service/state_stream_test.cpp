// The decimated state stream (service/run/state_stream.h) on a state block the test publishes
// into as the loop does. What a client would notice if it broke: samples not every N-th tick,
// samples lost without being counted, a slow reader's backlog growing without bound, a stream
// that goes on after it was stopped or its client left.
#include "service/run/state_stream.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "telemetry/state_block.h"

namespace hapticd::service {
namespace {

using nlohmann::json;

void publish(telemetry::StateBlock& block, std::uint64_t from, std::uint64_t to) {
  for (std::uint64_t n = from; n < to; ++n) {
    client::StateSample s;
    s.tick = 1000 + n;
    s.x[0] = 0.001 * static_cast<double>(n);
    block.publish(s);
  }
}

std::vector<json> lines(const std::string& out) {
  std::vector<json> v;
  std::istringstream in(out);
  for (std::string l; std::getline(in, l);) v.push_back(json::parse(l));
  return v;
}

TEST(StateStream, EveryNthSampleFromTheNextOneWithItsCrtkNames) {
  telemetry::StateBlock block(64, 1'000'000, 3, 3);
  publish(block, 0, 5);
  StateStream stream(block.fd());
  const json answer = stream.subscribe(7, 10);
  EXPECT_EQ(answer["every"], 10);
  EXPECT_EQ(answer["rate_hz"], 100.0);
  EXPECT_EQ(answer["first_sample"], 5);
  EXPECT_EQ(stream.wait_ms(), 10);
  std::string out;
  EXPECT_FALSE(stream.push(7, 0, out)) << "nothing new yet";
  publish(block, 5, 40);
  EXPECT_TRUE(stream.push(7, 0, out));
  const std::vector<json> got = lines(out);
  ASSERT_EQ(got.size(), 4u);  // samples 5, 15, 25, 35
  for (std::size_t i = 0; i < got.size(); ++i) {
    const json& s = got[i]["stream"];
    EXPECT_EQ(got[i]["v"], 1);
    EXPECT_FALSE(got[i].contains("ok")) << "a stream line is never an answer";
    EXPECT_EQ(s["tick"], 1005 + 10 * i);
    EXPECT_DOUBLE_EQ(s["measured_cp"][0].get<double>(), 0.001 * static_cast<double>(5 + 10 * i));
    EXPECT_EQ(s["measured_js"]["position"].size(), 3u);
    EXPECT_EQ(s["missed"], 0);
  }
  EXPECT_FALSE(stream.push(8, 0, out)) << "a client that asked for no stream gets none";
}

// A reader whose output is not sent (it does not read) gets nothing queued beyond the backlog:
// what fell due meanwhile is counted, and said on the next line it reads.
TEST(StateStream, ASlowReadersSamplesAreCountedMissedNotQueued) {
  telemetry::StateBlock block(1024, 1'000'000, 3, 3);
  StateStream stream(block.fd());
  stream.subscribe(1, 1);
  publish(block, 0, 100);
  std::string out;
  EXPECT_FALSE(stream.push(1, StateStream::kBacklogBytes + 1, out));
  EXPECT_TRUE(out.empty());
  publish(block, 100, 101);
  EXPECT_TRUE(stream.push(1, 0, out));
  const std::vector<json> got = lines(out);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0]["stream"]["tick"], 1100);
  EXPECT_EQ(got[0]["stream"]["missed"], 100);
  const json stopped = stream.subscribe(1, 0);
  EXPECT_EQ(stopped["sent"], 1);
  EXPECT_EQ(stopped["missed"], 100);
  EXPECT_FALSE(stream.streaming(1));
  EXPECT_EQ(stream.wait_ms(), -1);
}

// The ring went round before the stream was read: what was overwritten is counted, the rest
// sent in order.
TEST(StateStream, SamplesTheRingOverwroteAreCountedMissed) {
  telemetry::StateBlock block(16, 1'000'000, 2, 2);
  StateStream stream(block.fd());
  stream.subscribe(3, 2);
  publish(block, 0, 40);  // samples 0..23 overwritten: 0, 2, ..., 22 missed
  std::string out;
  EXPECT_TRUE(stream.push(3, 0, out));
  const std::vector<json> got = lines(out);
  ASSERT_EQ(got.size(), 8u);  // 24, 26, ..., 38
  EXPECT_EQ(got.front()["stream"]["tick"], 1024);
  EXPECT_EQ(got.front()["stream"]["missed"], 12);
  EXPECT_EQ(got.front()["stream"]["measured_cp"].size(), 2u);
  stream.leave(3);
  EXPECT_FALSE(stream.streaming(3));
}

}  // namespace
}  // namespace hapticd::service
