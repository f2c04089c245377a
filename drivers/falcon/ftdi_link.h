// What the Falcon's driver needs of its USB link (docs/drivers/falcon.md): the FT232's vendor
// requests and its two bulk endpoints. The libusb transport implements it for the device; the
// tests implement it over a simulated bootloader. Not RT code: the load and homing use it
// before the first tick.
#pragma once

#include <span>
#include <string>

#include "drivers/falcon/falcon_protocol.h"

namespace hapticd::drivers::falcon {

class FtdiLink {
 public:
  virtual ~FtdiLink() = default;
  // One vendor request (bmRequestType 0x40, wIndex 0). False with what the host said.
  virtual bool control(const FtdiRequest& r, std::string& error) = 0;
  // All of `data` to the bulk OUT endpoint within `timeout_ms`. False with the cause.
  virtual bool write(std::span<const unsigned char> data, int timeout_ms, std::string& error) = 0;
  // One bulk IN transfer into `buffer`, as the chip sends it (2 modem status bytes at the head
  // of each 64-byte USB packet): its length, 0 when nothing came within `timeout_ms`, -1 on an
  // error (in `error`: the device gone, a stall).
  virtual int read(std::span<unsigned char> buffer, int timeout_ms, std::string& error) = 0;
};

}  // namespace hapticd::drivers::falcon
