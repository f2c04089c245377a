// The configfs tree every USB gadget of the kernel test fixtures is made of: its ids and
// strings, configuration c.1 and one function in it (hid.usb0, acm.usb0). What differs between
// gadgets is the function's own attributes, written between make and link.
#pragma once

#include <cstdint>
#include <string>

namespace hapticd::kernel_test {

struct GadgetIdentity {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial, manufacturer, product;
};

// Makes `root` (under kUsbGadgets) with the ids, the strings, configuration c.1 called
// `configuration`, and the function's directory; returns the function's path.
std::string make_gadget_tree(const std::string& root, const GadgetIdentity& id,
                             const std::string& configuration, const std::string& function);
// Puts the function, its attributes written, into configuration c.1.
void link_gadget_function(const std::string& root, const std::string& function);
// Best effort and in reverse order (configfs refuses to remove a directory still in use); the
// gadget must be off its controller already.
void remove_gadget_tree(const std::string& root, const std::string& function) noexcept;

}  // namespace hapticd::kernel_test
