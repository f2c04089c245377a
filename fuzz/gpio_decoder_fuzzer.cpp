// libFuzzer target for the GPIO driver's pure codecs: the x4 quadrature decoder fed an
// arbitrary edge stream (any lines, levels, and times that may run backwards), checked after
// every edge against an independent model of the count; and the loopback wire format, whose
// every accepted message must re-encode to the same bytes.
//
// Input: byte 0 flags (bit 0 index, bits 1-2 the rate limit: none, 1 kHz, 100 kHz, 10 MHz),
// bytes 1-8 start_count, 9-16 index_count (little-endian), then 3 bytes an edge: a signed time
// step in us, the line (0-3) and the level (bit 2 of the same byte); the tail after a 0xff
// 0xff 0xff marker goes to the wire decoders.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>

#include "drivers/gpio/gpio_wire.h"
#include "drivers/gpio/quadrature_decoder.h"
#include "support/check.h"

namespace {

using hapticd::fuzz::require;
namespace g = hapticd::drivers::gpio;

std::int64_t le64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return static_cast<std::int64_t>(v);
}

// The model: levels per line, and the count moved by the textbook rule for one changed line
// (A changed: forward when A now differs from B; B changed: forward when B now equals A).
struct Model {
  bool a = false, b = false, index = false;
  std::uint64_t count = 0;
  std::uint64_t repeated = 0, out_of_order = 0;
  std::int64_t last_ab_ns = 0;
  bool have_last = false;
};

void check_wire(std::span<const std::uint8_t> msg) {
  std::array<std::uint8_t, g::wire::kMaxMessageSize> out{};
  g::wire::Output o;
  if (g::wire::decode_output(msg, o)) {
    require(g::wire::encode_output(o, out) == msg.size() &&
                std::memcmp(out.data(), msg.data(), msg.size()) == 0,
            "an accepted output message re-encodes to itself");
  }
  g::wire::Levels l;
  if (g::wire::decode_levels(msg, l)) {
    require(g::wire::encode_levels(l, out) == msg.size() &&
                std::memcmp(out.data(), msg.data(), msg.size()) == 0,
            "an accepted levels message re-encodes to itself");
  }
  g::wire::EdgesHeader h;
  if (g::wire::decode_edges_header(msg, h)) {
    std::array<g::Edge, g::wire::kMaxEdgesPerMessage> edges;
    std::size_t n = 0;
    for (; n < h.count && g::wire::decode_edge(msg, n, edges[n]); ++n) {
    }
    if (n == h.count) {
      require(g::wire::encode_edges(h.complete_until_ns, {edges.data(), n}, out) == msg.size() &&
                  std::memcmp(out.data(), msg.data(), msg.size()) == 0,
              "an accepted edge batch re-encodes to itself");
    }
  }
  g::wire::Type t;
  g::wire::peek_type(msg, t);
  g::wire::decode_hello(msg);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 17) return 0;
  constexpr double kRates[] = {0.0, 1e3, 1e5, 1e7};
  g::DecoderConfig c;
  c.has_index = (data[0] & 1u) != 0;
  c.max_edge_rate_hz = kRates[(data[0] >> 1) & 3u];
  c.start_count = le64(data + 1);
  c.index_count = le64(data + 9);
  g::QuadratureDecoder d(c);
  d.reset(0);
  Model m;
  m.count = static_cast<std::uint64_t>(c.start_count);
  std::int64_t t = 1'000'000'000;
  std::size_t i = 17;
  for (; i + 3 <= size; i += 3) {
    if (data[i] == 0xff && data[i + 1] == 0xff && data[i + 2] == 0xff) break;
    t += static_cast<std::int8_t>(data[i]) * 1000;
    const g::Edge e{t, 0, static_cast<g::Line>(data[i + 1] & 3u), (data[i + 1] & 4u) != 0};
    const std::uint64_t missed_before = d.missed_edges();
    d.apply(e);
    if (e.line == g::Line::kA || e.line == g::Line::kB) {
      if (m.have_last && t < m.last_ab_ns) ++m.out_of_order;
      m.last_ab_ns = t;
      m.have_last = true;
      bool& mine = e.line == g::Line::kA ? m.a : m.b;
      if (mine == e.level) {
        ++m.repeated;
      } else {
        mine = e.level;
        const bool forward = e.line == g::Line::kA ? (m.a != m.b) : (m.b == m.a);
        m.count += forward ? 1 : static_cast<std::uint64_t>(-1);
      }
    } else if (e.line == g::Line::kIndex) {
      if (c.has_index && e.level && !m.index) m.count = static_cast<std::uint64_t>(c.index_count);
      m.index = e.level;
    }
    require(
        static_cast<std::uint64_t>(d.count()) == m.count, "the count follows the model",
        std::to_string(d.count()) + " vs " + std::to_string(static_cast<std::int64_t>(m.count)));
    require(d.repeated_levels() == m.repeated, "repeated levels counted");
    require(d.out_of_order() == m.out_of_order, "out-of-order edges counted");
    require(d.missed_edges() >= missed_before, "missed edges never decrease");
    require(c.max_edge_rate_hz > 0.0 || (!d.rate_exceeded() && d.illegal_transitions() == 0),
            "no rate limit: nothing is too fast or illegal");
    require(d.illegal_transitions() <= d.edges(), "at most one illegal transition an edge");
  }
  if (i + 3 <= size) check_wire({data + i + 3, size - i - 3});
  return 0;
}
