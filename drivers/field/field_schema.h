// How a configuration names a field (field.h): {byte, type, endian}, or a field of any width at
// any bit, {byte, bit, bits, signed, endian}; then scale and offset for a quantity. The HID
// driver's vendor reports and the serial driver's frames describe their fields with the same
// keys, read here once. Pure: no OS header.
#pragma once

#include <cstddef>

#include "config/schema_reader.h"
#include "drivers/field/field.h"

namespace hapticd::drivers::field {

// Not RT-safe. Reads one field's keys from `m` (the field's mapping); every problem is reported
// through `m` at the key to change. `max_byte`: the largest byte offset the message can have.
// `quantity`: the field holds an SI value, so `scale` (required) and `offset` are read.
FieldSpec read_spec(config::schema::MapReader& m, std::size_t max_byte, bool quantity);

}  // namespace hapticd::drivers::field
