// The driver's own firmware loader (drivers/falcon/firmware_loader.h) against the simulated
// Falcon (sim/peers/falcon/) over a real socketpair: the loader's steps are what the peer's
// bootloader answers, a first try that fails is retried, and the peer serves the load from its
// own thread (PeerRunner) with the loader's default timing, as a loopback run would.
#include <gtest/gtest.h>

#include <string>

#include "drivers/falcon/firmware_loader.h"
#include "falcon_peer_rig.h"
#include "sim/peers/falcon/falcon_peer_entry.h"
#include "sim/peers/peer_runner.h"

namespace hapticd::sim::falcon::testing {
namespace {

// Short waits: a pumped peer has answered before the loader reads.
constexpr df::LoaderTiming kFast{5, 3, 50, 5, 3};

TEST(FalconPeerLoad, TheDriversLoaderLoadsThePeerOnTheFirstTry) {
  Rig rig;
  const auto image = falcon_image_bytes();
  const df::LoadResult r = df::load_firmware(*rig.host, image, 3, kFast);
  ASSERT_TRUE(r.loaded) << df::describe(r);
  EXPECT_EQ(r.tries.size(), 1u);
  EXPECT_EQ(rig.peer->loads_completed(), 1);
  EXPECT_TRUE(rig.peer->firmware_running());
  EXPECT_EQ(rig.peer->chip().image_bytes(), image.size());
  EXPECT_EQ(rig.peer->chip().divisor(), 2);
  EXPECT_EQ(rig.peer->chip().latency_ms(), 1);
  EXPECT_GE(rig.peer->packets_answered(), 1u) << "the loader's proof that the firmware runs";
  EXPECT_FALSE(rig.peer->output_on()) << "the loader's packet commands no force";
}

TEST(FalconPeerLoad, ABootloaderThatIgnoresTheFirstTryLoadsOnTheSecond) {
  FalconPeerOptions o;
  o.fail_first_load = true;
  Rig rig(o);
  const df::LoadResult r = df::load_firmware(*rig.host, falcon_image_bytes(), 3, kFast);
  ASSERT_TRUE(r.loaded) << df::describe(r);
  ASSERT_EQ(r.tries.size(), 2u);
  EXPECT_NE(r.tries[0].failed_at.find("first check"), std::string::npos) << df::describe(r);
  EXPECT_EQ(r.tries[0].saw, "nothing");
  EXPECT_EQ(rig.peer->resets(), 2) << "each try resets the microcontroller";
  EXPECT_EQ(rig.peer->loads_completed(), 1);
}

TEST(FalconPeerLoad, AWrongFileIsEchoedButNeverRuns) {
  Rig rig;
  const df::LoadResult r = df::load_firmware(*rig.host, falcon_image_bytes(1000), 2, kFast);
  EXPECT_FALSE(r.loaded);
  ASSERT_EQ(r.tries.size(), 2u);
  EXPECT_NE(r.tries[1].failed_at.find("the firmware never answered"), std::string::npos)
      << df::describe(r);
  EXPECT_EQ(rig.peer->loads_completed(), 0);
}

TEST(FalconPeerLoad, AHungDeviceFailsEveryTryAtTheFirstCheck) {
  Rig rig;
  ASSERT_TRUE(rig.peer->inject(PeerFault::kStopAnswering));
  const df::LoadResult r = df::load_firmware(*rig.host, falcon_image_bytes(), 2, kFast);
  EXPECT_FALSE(r.loaded);
  for (const df::LoadTry& t : r.tries)
    EXPECT_NE(t.failed_at.find("0a 44 2c 0d"), std::string::npos);
}

TEST(FalconPeerLoad, AnUnpluggedDeviceFailsWithWhatTheHostSaw) {
  Rig rig;
  ASSERT_TRUE(rig.peer->inject(PeerFault::kTransportFault));
  const df::LoadResult r = df::load_firmware(*rig.host, falcon_image_bytes(), 1, kFast);
  EXPECT_FALSE(r.loaded);
  ASSERT_EQ(r.tries.size(), 1u);
  EXPECT_NE(r.tries[0].failed_at.find("refused"), std::string::npos) << df::describe(r);
}

TEST(FalconPeerLoad, ThePeerOnItsOwnThreadLoadsWithTheLoadersDefaultTiming) {
  FalconPeerOptions o;
  o.fail_first_load = true;
  Rig rig(o, {}, /*pumped=*/false);
  PeerRunner runner(*rig.peer);
  const df::LoadResult r = df::load_firmware(*rig.host, falcon_image_bytes(8492), 3);
  runner.stop();
  EXPECT_EQ(runner.error(), "");
  ASSERT_TRUE(r.loaded) << df::describe(r);
  EXPECT_EQ(r.tries.size(), 2u);
  EXPECT_EQ(rig.peer->loads_completed(), 1);
}

TEST(FalconPeerLoad, TheEntryAnswersForTheFalconDriver) {
  const PeerEntry e = peer_entry();
  EXPECT_EQ(e.driver, "falcon");
  ASSERT_NE(e.make_peer, nullptr);
  auto [host, end] = io::seqpacket_pair();
  const auto peer = e.make_peer(sim_delta(), std::move(end));
  ASSERT_NE(peer, nullptr);
  EXPECT_NE(peer->joint_plant(), nullptr);
  EXPECT_EQ(peer->joint_plant()->joints(), 3);
}

}  // namespace
}  // namespace hapticd::sim::falcon::testing
