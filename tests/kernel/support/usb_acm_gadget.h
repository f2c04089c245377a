// A real USB serial device inside the kernel test machine: a configfs gadget with one CDC-ACM
// function on the dummy_hcd controller, so the kernel's own cdc_acm driver binds on the host
// side and makes /dev/ttyACMn, as it does for a microcontroller's native USB port. The device's
// end is the gadget's tty, /dev/ttyGSn (u_serial): what a test's device writes there arrives
// at the host's ttyACM, and what the host writes is read there. unplug() unbinds the gadget
// from the controller: the host sees the disconnect and hangs its ttyACM up, as on a cable
// pulled. dummy_hcd has one controller, so one gadget at a time.
#pragma once

#include <cstdint>
#include <string>

namespace hapticd::kernel_test {

struct UsbAcmGadgetConfig {
  std::uint16_t vendor_id = 0x1209;  // pid.codes' test vendor id
  std::uint16_t product_id = 0x0002;
  std::string serial = "hapticd-acm";
  std::string manufacturer = "hapticd";
  std::string product = "hapticd serial test device";
  std::string name = "hapticd-acm";  // the configfs directory under usb_gadget/
};

class UsbAcmGadget {
 public:
  // Creates the gadget, binds it and waits (up to 20 s: emulated machines are slow) until the
  // host side has enumerated it and made its ttyACM node.
  explicit UsbAcmGadget(UsbAcmGadgetConfig config = {});
  ~UsbAcmGadget();  // unplugs, removes the configfs tree
  UsbAcmGadget(const UsbAcmGadget&) = delete;
  UsbAcmGadget& operator=(const UsbAcmGadget&) = delete;

  const std::string& host_path() const noexcept { return host_path_; }      // /dev/ttyACMn
  const std::string& device_path() const noexcept { return device_path_; }  // /dev/ttyGSn
  // The gadget off the controller (idempotent): the host's ttyACM hangs up and goes away.
  void unplug();

 private:
  void create_configfs_tree();
  void remove_configfs_tree() noexcept;
  std::string find_host_tty() const;  // "" until cdc_acm has bound

  UsbAcmGadgetConfig config_;
  std::string root_;
  std::string host_path_, device_path_;
};

}  // namespace hapticd::kernel_test
