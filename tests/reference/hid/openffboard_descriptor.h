// The report descriptors of OpenFFBoard, firmware commit 160af910, 16-bit axes: the FFBWheel's
// (one axis, UserExtensions/Src/usb_hid_1ffb_desc.c, hid_1ffb_desc) and the FFB Joystick (2
// Axis)'s (UserExtensions/Src/usb_hid_2ffb_desc.c, hid_2ffb_desc, which FFBJoystick.cpp line
// 39 installs), and the blocks they are made of in UserExtensions/Inc/usb_hid_ffb_desc.h,
// item by item with the same meaning (HID 1.11 6.2.2), written with this file's own item
// writer. Report ids are those of Inc/ffb_defs.h.
#pragma once

#include <cstdint>
#include <vector>

namespace hapticd::reference {

// `axes` 1: hid_1ffb_desc; 2: hid_2ffb_desc. The two differ only in the Set Effect report's
// Axes Enable, Direction and Type Specific Block Offset, and in the Set Condition report.
std::vector<std::uint8_t> openffboard_descriptor(int axes = 1);

}  // namespace hapticd::reference
