#include "usb_gadget_tree.h"

#include <unistd.h>

#include "sysfs.h"

namespace hapticd::kernel_test {

std::string make_gadget_tree(const std::string& root, const GadgetIdentity& id,
                             const std::string& configuration, const std::string& function) {
  make_dir(root);
  write_text(root + "/idVendor", "0x" + hex4(id.vendor_id));
  write_text(root + "/idProduct", "0x" + hex4(id.product_id));
  write_text(root + "/bcdUSB", "0x0200");
  make_dir(root + "/strings/0x409");
  write_text(root + "/strings/0x409/serialnumber", id.serial);
  write_text(root + "/strings/0x409/manufacturer", id.manufacturer);
  write_text(root + "/strings/0x409/product", id.product);
  make_dir(root + "/configs/c.1");
  make_dir(root + "/configs/c.1/strings/0x409");
  write_text(root + "/configs/c.1/strings/0x409/configuration", configuration);
  const std::string path = root + "/functions/" + function;
  make_dir(path);
  return path;
}

void link_gadget_function(const std::string& root, const std::string& function) {
  if (::symlink((root + "/functions/" + function).c_str(),
                (root + "/configs/c.1/" + function).c_str()) != 0) {
    throw_errno("link function " + function + " into configuration c.1");
  }
}

void remove_gadget_tree(const std::string& root, const std::string& function) noexcept {
  ::unlink((root + "/configs/c.1/" + function).c_str());
  remove_dir(root + "/configs/c.1/strings/0x409");
  remove_dir(root + "/configs/c.1");
  remove_dir(root + "/functions/" + function);
  remove_dir(root + "/strings/0x409");
  remove_dir(root);
}

}  // namespace hapticd::kernel_test
