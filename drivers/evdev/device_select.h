// Choosing the one input device a configuration means (device.evdev.select), and the listing
// `hapticd devices` prints: each device with force feedback and the select: mapping that picks
// it out. Pure: the enumeration itself is libevdev's (libevdev_transport.h).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivers/evdev/evdev_settings.h"

namespace hapticd::drivers::evdev {

// One /dev/input/eventN as the kernel describes it.
struct InputListing {
  std::string path;                // /dev/input/eventN
  std::vector<std::string> links;  // /dev/input/by-id/ and by-path/ links to it
  std::string name, phys, uniq;
  std::uint16_t bus = 0, vendor_id = 0, product_id = 0;
  bool ff_constant = false, ff_gain = false, ff_autocenter = false;
  int ff_effects = 0;
  std::vector<int> abs_axes;    // the single absolute axes it has
  std::string kernel_driver;    // what sysfs names as the driver bound to it ("" if none)
  bool virtual_device = false;  // made in user space (uinput): no bus of its own
};

// The class of kernel force-feedback driver behind a listing, where it can be told from the
// driver's name; nothing for a driver not known here.
std::optional<FfDriver> guess_ff_driver(const InputListing& d);

// Every listing the selector matches (its given keys all equal; `path` alone, as the node or a
// link to it, when given). `resolved_path` is `select.path` with its links followed.
std::vector<InputListing> matching(const Selector& s, const std::string& resolved_path,
                                   const std::vector<InputListing>& all);

// "name 'X', vendor_id 0x046d": what the selector asks for.
std::string describe(const Selector& s);

struct Selection {
  std::optional<InputListing> device;
  std::string error;  // why there is none: nothing matches, or several do (with what is there)
};
Selection select_one(const Selector& s, const std::string& resolved_path,
                     const std::vector<InputListing>& all);

// The `hapticd devices` text: each device with FF_CONSTANT, with its select: mapping (name
// and ids, phys or uniq added where those alone match several), and how many others there are.
std::string format_listing(const std::vector<InputListing>& all, int unreadable);

}  // namespace hapticd::drivers::evdev
