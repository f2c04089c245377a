// Loading Novint's firmware into the Falcon (docs/drivers/falcon.md, "The FTDI set-up and the
// bootloader"): the steps of libnifalcon's setFirmwareMode, loadFirmware and setNormalMode,
// then the firmware's first answer, tried up to a bounded number of times. Users of libnifalcon
// report loads that fail until tried again (its issues 24, 33, 45, 67); each try here records
// the step it failed at and the bytes it saw there, so a refusal says what the device did.
// Not RT code: runs in configure.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "drivers/falcon/ftdi_link.h"

namespace hapticd::drivers::falcon {

struct LoaderTiming {
  int reply_ms = 100;       // the bootloader's answer to a check
  int check_writes = 20;    // first-check writes a try makes (libnifalcon: up to 100)
  int echo_ms = 1000;       // one 128-byte chunk's echo (9 ms at the loading rate)
  int answer_ms = 50;       // the running firmware's answer to a packet
  int answer_packets = 10;  // packets sent before the firmware is called silent (libnifalcon: 10)
};

struct LoadTry {
  std::string failed_at;  // empty: this try loaded the firmware
  std::string saw;        // the data bytes seen at that step, hex ("nothing" when none)
};

struct LoadResult {
  bool loaded = false;
  std::vector<LoadTry> tries;
};

// The image's bytes from `path`, or std::runtime_error naming the file: unreadable, or a size
// outside kFirmwareMinBytes..kFirmwareMaxBytes (with where libnifalcon says Novint's images are).
std::vector<unsigned char> read_firmware_image(const std::string& path);

// Up to `max_tries` loads of `image` through `link`; stops at the first that loads.
LoadResult load_firmware(FtdiLink& link, std::span<const unsigned char> image, int max_tries,
                         const LoaderTiming& timing = {});

// Whether Novint's firmware already runs (it stays loaded while the device has power: a
// restarted hapticd finds it): the normal mode's requests, then a packet answered within
// timing.answer_packets tries. Never resets the device.
bool firmware_running(FtdiLink& link, const LoaderTiming& timing = {});

// "try 1: <step>: saw <bytes>; try 2: loaded" - for the log and the refusal.
std::string describe(const LoadResult& r);

}  // namespace hapticd::drivers::falcon
