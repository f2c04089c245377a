// libFuzzer target for the HID driver's pure codecs (drivers/hid/). Byte 0 & 3 says what the
// rest of the input is (read as support/hid_input.h says); the invariants are in the headers:
//   0  a report descriptor, and the PID layout found in it (bit 2 of byte 0: with the
//      reference sequence usage): support/hid_descriptor_oracle.h;
//   1  a `report` profile layout, max_force, values and a report: support/hid_layout_oracle.h;
//   2  a loopback message: support/hid_frame_oracle.h;
//   3  an offset, a width and a value for get_bits/put_bits over the tail:
//      support/hid_bits_oracle.h.
#include <cstddef>
#include <cstdint>

#include "support/hid_bits_oracle.h"
#include "support/hid_descriptor_oracle.h"
#include "support/hid_frame_oracle.h"
#include "support/hid_input.h"
#include "support/hid_layout_oracle.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace fuzz = hapticd::fuzz;
  if (size == 0) return 0;
  fuzz::HidInput r({data + 1, size - 1});
  const unsigned mode = data[0] & 3u;
  if (mode == 0) fuzz::check_hid_descriptor(r.rest(), (data[0] & 4u) != 0);
  if (mode == 1) fuzz::check_hid_layout(r);
  if (mode == 2) fuzz::check_hid_frame(r.rest());
  if (mode == 3) fuzz::check_hid_bits(r);
  return 0;
}
