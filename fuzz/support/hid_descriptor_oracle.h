// What the hid_codec fuzz target asserts about a HID report descriptor (drivers/hid/
// report_descriptor.h) and the PID layout found in it (drivers/hid/pid_protocol.h).
#pragma once

#include <cstdint>
#include <span>

namespace hapticd::fuzz {

// Parses `bytes` as a report descriptor. A refusal must say why and, for an item's error, name
// a byte inside the input ("byte N: ..."). A parse must keep report_descriptor.h's promises:
// reports unique by kind and id and numbered all or none, each 1 bit to 4096 bytes and exactly
// its fields' bits, fields bounded and following one another. Then find_pid_layout (with the
// reference sequence usage when `with_sequence`) must give a layout or an error, never both;
// a layout's reports must be the descriptor's, made and recognised by id and length, and every
// slot and choice written and read back in a report filled with `bytes`, touching no other bit,
// with a null value that reads outside the logical range whenever the slot's width has one;
// pid_status must set exactly the bits the layout's state fields say.
void check_hid_descriptor(std::span<const std::uint8_t> bytes, bool with_sequence);

}  // namespace hapticd::fuzz
