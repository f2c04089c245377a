// The x4 quadrature decoder: every legal and illegal transition, a direction change at every
// state, missed edges of every kind, the rate limit, index re-zeroing and counts that wrap.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "drivers/gpio/gpio_transport.h"
#include "drivers/gpio/quadrature_decoder.h"

namespace hapticd::drivers::gpio {
namespace {

constexpr std::uint8_t k00 = 0, kA1 = kBitA, k11 = kBitA | kBitB, kB1 = kBitB;
// The forward sequence (A leads B): 00 -> A -> AB -> B -> 00.
constexpr std::uint8_t kForward[4] = {k00, kA1, k11, kB1};

// The edge that takes `from` to `to` (one bit apart).
Edge edge_between(std::uint8_t from, std::uint8_t to, std::int64_t t) {
  const std::uint8_t d = from ^ to;
  Edge e;
  e.time_ns = t;
  e.line = (d & kBitA) != 0 ? Line::kA : Line::kB;
  e.level = (to & d) != 0;
  return e;
}

TEST(QuadratureTransition, EveryPairOfStates) {
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const Transition t = transition(kForward[i], kForward[j]);
      const int d = (j - i + 4) % 4;
      SCOPED_TRACE(testing::Message() << "from " << int(kForward[i]) << " to " << int(kForward[j]));
      const Transition expected[4] = {Transition::kNone, Transition::kForward, Transition::kIllegal,
                                      Transition::kBackward};
      EXPECT_EQ(t, expected[d]) << "distance " << d << " along the sequence (2: both bits)";
    }
  }
}

TEST(QuadratureTransition, StateOfCountFollowsTheSequenceForNegativeCountsToo) {
  for (std::int64_t c = -9; c <= 9; ++c) {
    EXPECT_EQ(transition(state_of_count(c), state_of_count(c + 1)), Transition::kForward) << c;
  }
  EXPECT_EQ(state_of_count(0), k00);
  EXPECT_EQ(state_of_count(-1), kB1);
}

class DecoderAtEveryState : public testing::TestWithParam<int> {};

TEST_P(DecoderAtEveryState, ForwardAndBackwardEdgesCountOne) {
  const std::uint8_t s = kForward[GetParam()];
  QuadratureDecoder d({});
  d.reset(s);
  d.apply(edge_between(s, kForward[(GetParam() + 1) % 4], 100));
  EXPECT_EQ(d.count(), 1);
  d.reset(s);
  d.apply(edge_between(s, kForward[(GetParam() + 3) % 4], 100));
  EXPECT_EQ(d.count(), -1);
  EXPECT_EQ(d.missed_edges(), 0u);
}

TEST_P(DecoderAtEveryState, DirectionChangesAtThisState) {
  // Arrive at the state going forward, leave it going backward, and the other way round:
  // a reversal is legal, whichever line it happens on.
  const int i = GetParam();
  const std::uint8_t before = kForward[(i + 3) % 4], here = kForward[i],
                     after = kForward[(i + 1) % 4];
  QuadratureDecoder d({});
  d.reset(before);
  d.apply(edge_between(before, here, 1000));
  d.apply(edge_between(here, before, 2000));
  EXPECT_EQ(d.count(), 0);
  d.apply(edge_between(before, here, 3000));
  d.apply(edge_between(here, after, 4000));
  d.apply(edge_between(after, here, 5000));
  d.apply(edge_between(here, after, 6000));
  EXPECT_EQ(d.count(), 2);
  EXPECT_EQ(d.state(), after);
  EXPECT_EQ(d.missed_edges(), 0u);
}

TEST_P(DecoderAtEveryState, RepeatedLevelIsAMissedEdgeOnEitherLine) {
  const std::uint8_t s = kForward[GetParam()];
  for (Line line : {Line::kA, Line::kB}) {
    QuadratureDecoder d({});
    d.reset(s);
    Edge e;
    e.time_ns = 10;
    e.line = line;
    e.level = (s & (line == Line::kA ? kBitA : kBitB)) != 0;  // the level it already has
    d.apply(e);
    EXPECT_EQ(d.repeated_levels(), 1u);
    EXPECT_EQ(d.missed_edges(), 1u);
    EXPECT_EQ(d.count(), 0) << "the line changed twice: net nothing";
    EXPECT_EQ(d.state(), s);
  }
}

TEST_P(DecoderAtEveryState, BothBitsWithinTheResolutionIsIllegal) {
  const int i = GetParam();
  const std::uint8_t s0 = kForward[i], s1 = kForward[(i + 1) % 4], s2 = kForward[(i + 2) % 4];
  DecoderConfig c;
  c.max_edge_rate_hz = 10'000;  // resolution 100 us
  QuadratureDecoder d(c);
  d.reset(s0);
  d.apply(edge_between(s0, s1, 1'000'000));
  d.apply(edge_between(s1, s2, 1'000'000 + 40'000));  // 40 us later: both bits "at once"
  EXPECT_EQ(d.illegal_transitions(), 1u);
  EXPECT_EQ(d.count(), 2) << "applied in timestamp order, but counted as missed";
  // The same pair further apart is two legal steps.
  QuadratureDecoder ok(c);
  ok.reset(s0);
  ok.apply(edge_between(s0, s1, 1'000'000));
  ok.apply(edge_between(s1, s2, 1'000'000 + 150'000));
  EXPECT_EQ(ok.missed_edges(), 0u);
  EXPECT_EQ(ok.count(), 2);
}

TEST_P(DecoderAtEveryState, ObservedLevelsResynchronise) {
  const int i = GetParam();
  const std::uint8_t s = kForward[i];
  QuadratureDecoder d({});
  d.reset(s);
  d.observe(kForward[(i + 1) % 4]);  // one edge whose event never came: direction known
  EXPECT_EQ(d.count(), 1);
  EXPECT_EQ(d.lost(), 1u);
  d.observe(kForward[(i + 3) % 4]);  // two bits from there: illegal, direction unknown
  EXPECT_EQ(d.illegal_transitions(), 1u);
  EXPECT_EQ(d.count(), 1) << "an illegal transition moves nothing";
  EXPECT_EQ(d.state(), kForward[(i + 3) % 4]);
  d.observe(kForward[(i + 3) % 4]);
  EXPECT_EQ(d.missed_edges(), 2u);
}

INSTANTIATE_TEST_SUITE_P(States, DecoderAtEveryState, testing::Range(0, 4));

TEST(QuadratureDecoder, FullCyclesCountFourPerCycleBothWays) {
  QuadratureDecoder d({});
  d.reset(k00);
  std::int64_t t = 0;
  for (int k = 0; k < 40; ++k)
    d.apply(edge_between(kForward[k % 4], kForward[(k + 1) % 4], t += 100));
  EXPECT_EQ(d.count(), 40);
  for (int k = 40; k > 0; --k)
    d.apply(edge_between(kForward[k % 4], kForward[(k + 3) % 4], t += 100));
  EXPECT_EQ(d.count(), 0);
  EXPECT_EQ(d.edges(), 80u);
}

TEST(QuadratureDecoder, RandomWalkMatchesTheTrueCount) {
  std::mt19937 rng(7);
  QuadratureDecoder d({.start_count = -5});
  std::int64_t truth = -5;
  d.reset(state_of_count(truth));
  for (int k = 0; k < 10000; ++k) {
    const std::int64_t next = truth + ((rng() & 1u) ? 1 : -1);
    d.apply(edge_between(state_of_count(truth), state_of_count(next), 1000 * k));
    truth = next;
  }
  EXPECT_EQ(d.count(), truth);
  EXPECT_EQ(d.missed_edges(), 0u);
}

TEST(QuadratureDecoder, OlderEdgeIsOutOfOrder) {
  QuadratureDecoder d({});
  d.reset(k00);
  d.apply(edge_between(k00, kA1, 5000));
  d.apply(edge_between(kA1, k11, 4000));
  EXPECT_EQ(d.out_of_order(), 1u);
  EXPECT_EQ(d.count(), 2);
}

TEST(QuadratureDecoder, LostEventsCountAsMissed) {
  QuadratureDecoder d({});
  d.add_lost(3);
  EXPECT_EQ(d.lost(), 3u);
  EXPECT_EQ(d.missed_edges(), 3u);
}

TEST(QuadratureDecoder, RateAboveTheLimitOverTheWindowLatches) {
  DecoderConfig c;
  c.max_edge_rate_hz = 1000;  // 1 ms
  // At the limit (1 ms apart), and a single close pair, are fine.
  QuadratureDecoder d(c);
  d.reset(k00);
  std::int64_t t = 0;
  for (int k = 0; k < 40; ++k)
    d.apply(edge_between(kForward[k % 4], kForward[(k + 1) % 4], t += 1'000'000));
  EXPECT_FALSE(d.rate_exceeded());
  // Eight edges in 4 ms: 2000 edges/s.
  for (int k = 40; k < 48; ++k)
    d.apply(edge_between(kForward[k % 4], kForward[(k + 1) % 4], t += 500'000));
  EXPECT_TRUE(d.rate_exceeded());
  EXPECT_NEAR(d.exceeded_rate_hz(), 2000.0, 1.0);
  // No limit configured: nothing is too fast.
  QuadratureDecoder free({});
  free.reset(k00);
  for (int k = 0; k < 100; ++k) free.apply(edge_between(kForward[k % 4], kForward[(k + 1) % 4], k));
  EXPECT_FALSE(free.rate_exceeded());
  EXPECT_EQ(free.illegal_transitions(), 0u);
}

TEST(QuadratureDecoder, IndexRisingEdgeReZeroes) {
  DecoderConfig c;
  c.has_index = true;
  c.index_count = 1000;
  c.start_count = 5;
  QuadratureDecoder d(c);
  d.reset(k00);
  d.apply(edge_between(k00, kA1, 10));
  EXPECT_EQ(d.count(), 6);
  d.apply({20, 0, Line::kIndex, true});
  EXPECT_EQ(d.count(), 1000);
  EXPECT_EQ(d.index_hits(), 1u);
  d.apply(edge_between(kA1, k11, 30));
  EXPECT_EQ(d.count(), 1001);
  d.apply({40, 0, Line::kIndex, false});  // falling: nothing
  EXPECT_EQ(d.count(), 1001);
  d.apply({50, 0, Line::kIndex, true});  // every pass re-zeroes
  EXPECT_EQ(d.count(), 1000);
  EXPECT_EQ(d.index_hits(), 2u);
  // An index line that starts high re-zeroes only at its next rising edge.
  QuadratureDecoder high(c);
  high.reset(k00 | (1u << 2));
  EXPECT_TRUE(high.index_level());
  high.apply({10, 0, Line::kIndex, true});
  EXPECT_EQ(high.count(), 5);
  // Without an index configured the line is ignored.
  QuadratureDecoder none({.start_count = 5});
  none.reset(k00);
  none.apply({10, 0, Line::kIndex, true});
  EXPECT_EQ(none.count(), 5);
}

TEST(QuadratureDecoder, CountsWrapAtTheEndsOfTheRange) {
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  constexpr std::int64_t kMin = std::numeric_limits<std::int64_t>::min();
  QuadratureDecoder d({.start_count = kMax});
  d.reset(state_of_count(kMax));
  d.apply(edge_between(state_of_count(kMax), state_of_count(kMin), 10));
  EXPECT_EQ(d.count(), kMin) << "forward past the top wraps to the bottom";
  d.apply(edge_between(state_of_count(kMin), state_of_count(kMax), 20));
  EXPECT_EQ(d.count(), kMax) << "and back";
  EXPECT_EQ(d.missed_edges(), 0u) << "the Gray sequence continues across the wrap";
  DecoderConfig c;
  c.has_index = true;
  c.index_count = kMin;
  QuadratureDecoder idx(c);
  idx.reset(k00);
  idx.apply({5, 0, Line::kIndex, true});
  idx.apply(edge_between(state_of_count(kMin), state_of_count(kMax), 6));
  EXPECT_EQ(idx.count(), kMax) << "the index may set a count at the edge of the range";
}

// The kernel numbers a line request's edge events with a 32-bit counter (struct
// gpio_v2_line_event: __u32 seqno), as the loopback's wire does: after 2^32 events (two days at
// 25 000 edges a second) it passes 0xFFFFFFFF and continues at 0. Gaps are counted modulo 2^32,
// so the wrap is no gap and a gap across it is counted as one.
TEST(SequenceCheck, TheKernelsEventNumbersWrapAt32BitsWithoutAGap) {
  SequenceCheck seq;
  EXPECT_EQ(seq.next(0xFFFF'FFFEu), 0u) << "the first number sets the base";
  EXPECT_EQ(seq.next(0xFFFF'FFFFu), 0u);
  EXPECT_EQ(seq.next(0u), 0u) << "across the wrap";
  EXPECT_EQ(seq.next(1u), 0u);
  EXPECT_EQ(seq.next(4u), 2u) << "2 and 3 lost";
  seq.reset();
  EXPECT_EQ(seq.next(0xFFFF'FFFEu), 0u);
  EXPECT_EQ(seq.next(2u), 3u) << "0xFFFFFFFF, 0 and 1 lost, across the wrap";
  EXPECT_EQ(seq.next(1u), 1u) << "a number from the past: the stream cannot be trusted";
}

}  // namespace
}  // namespace hapticd::drivers::gpio
