// What the hid_codec fuzz target asserts about the loopback framing (drivers/hid/hid_framing.h):
// a message is a type byte and a payload, and whatever parses must rebuild byte for byte.
#pragma once

#include <cstdint>
#include <span>

namespace hapticd::fuzz {

// parse_frame must accept exactly the messages whose first byte is one of the eight types,
// with the rest as the payload; frame() and write_frame() must rebuild an accepted message,
// reply() a reply from its status byte and the rest, and get_feature_request() a Get Feature
// request from its id and 16-bit maximum length.
void check_hid_frame(std::span<const std::uint8_t> message);

}  // namespace hapticd::fuzz
