// The report descriptor of OpenFFBoard's FFBWheel (one axis, 16-bit axes), firmware commit
// 160af910: UserExtensions/Src/usb_hid_1ffb_desc.c (hid_1ffb_desc) and the blocks it is made
// of in UserExtensions/Inc/usb_hid_ffb_desc.h, item by item with the same meaning (HID 1.11
// 6.2.2), written with this file's own item writer. Report ids are those of Inc/ffb_defs.h.
#pragma once

#include <cstdint>
#include <vector>

namespace hapticd::reference {

std::vector<std::uint8_t> openffboard_descriptor();

}  // namespace hapticd::reference
