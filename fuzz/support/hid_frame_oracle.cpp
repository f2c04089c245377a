#include "support/hid_frame_oracle.h"

#include <algorithm>
#include <cstddef>
#include <iterator>
#include <optional>
#include <vector>

#include "drivers/hid/hid_framing.h"
#include "support/check.h"

namespace hapticd::fuzz {
namespace {

namespace hid = hapticd::drivers::hid;
using Bytes = std::vector<std::uint8_t>;

}  // namespace

void check_hid_frame(std::span<const std::uint8_t> m) {
  static constexpr std::uint8_t kTypes[] = {0x01, 0x02, 0x03, 0x04, 0x05, 0x83, 0x84, 0x85};
  const std::optional<hid::FrameView> v = hid::parse_frame(m);
  const bool known =
      !m.empty() && std::find(std::begin(kTypes), std::end(kTypes), m[0]) != std::end(kTypes);
  require(v.has_value() == known, "parse_frame takes exactly the eight message types");
  if (!v) return;
  require(v->payload.data() == m.data() + 1 && v->payload.size() == m.size() - 1,
          "the payload is the rest of the message");
  const Bytes same(m.begin(), m.end());
  require(hid::frame(v->type, v->payload) == same, "frame() rebuilds the message");
  Bytes out(m.size());
  require(hid::write_frame(v->type, v->payload, out) == m.size() && out == same,
          "write_frame rebuilds the message in a buffer of its size");
  const bool is_reply = (m[0] & 0x80u) != 0;
  if (is_reply && !v->payload.empty()) {
    require(hid::reply(v->type, v->payload[0], v->payload.subspan(1)) == same,
            "reply() rebuilds a reply from its status and payload");
  }
  if (v->type == hid::FrameType::kGetFeature && v->payload.size() == 3) {
    const auto max = static_cast<std::uint16_t>(v->payload[1] | v->payload[2] << 8);
    require(hid::get_feature_request(v->payload[0], max) == same, "get_feature_request");
  }
}

}  // namespace hapticd::fuzz
