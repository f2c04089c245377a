// What the hid_codec fuzz target asserts about a `report` profile layout (drivers/hid/
// report_layout.h): what validate() accepts must round-trip through the codecs, and any report
// must decode as documented.
#pragma once

#include "support/hid_input.h"

namespace hapticd::fuzz {

// Reads a layout: a byte whose bits say which optional parts follow (1 sequence, 2 status and
// fault mask, 4 velocity, 8 enable switch, 16 keepalive, 32/64/128 the enable, gain and
// watchdog features), then the input report (id, length, position, the parts present), the
// output report (id, length, force, full_scale, the parts present) and the features present,
// in the order of report_layout.h's structs. Then max_force. Every problem validate() finds
// must name where ("<where>: <what>"). A layout it accepts must give back, from the values read
// next, the position and velocity within a count's quantisation (a NaN position as raw 0), the
// sequence modulo its counter and the status clamped; the force clamped, never past
// full_scale counts, with the enable switch as written; each feature's value, and a switch
// that reads off after off. The rest of the input, as a report of any kind, must decode by id
// and length alone, a decoded force within +-full_scale counts.
void check_hid_layout(HidInput& input);

}  // namespace hapticd::fuzz
