// What the hid_codec fuzz target asserts about HID's little-endian bit packing
// (drivers/hid/report_descriptor.h), and the model it checks against, which the descriptor
// oracle uses for the PID slots too.
#pragma once

#include <cstdint>
#include <vector>

#include "support/hid_input.h"

namespace hapticd::fuzz {

// `d` with bits [offset, offset + bits) set to `value`'s low bits, where they lie inside it:
// bit i of the data is bit i % 8 of byte i / 8.
std::vector<std::uint8_t> put_bits_model(std::vector<std::uint8_t> d, std::uint64_t offset,
                                         std::uint32_t bits, std::uint32_t value);

// Reads a flags byte (bit 0: a 32-bit offset, else 16-bit), the offset, a width (mod 33) and a
// value; the rest of the input is the data. get_bits must read the model's bits (0 past the
// data), put_bits write exactly the model's, and get_bits read back what put_bits wrote inside
// the data; field_value must sign-extend a field of its own width and keep an unsigned field's
// value.
void check_hid_bits(HidInput& input);

}  // namespace hapticd::fuzz
