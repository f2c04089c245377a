// What the kernel tests of hapticd against the reference Falcon share: the test's firmware
// image, the settings that point the shipped config/falcon.yaml at the reference, the test's
// hand on the grip, and the waits for homing and for output.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "falcon_mechanism.h"
#include "hapticd_process.h"
#include "raw_usb_ftdi.h"

namespace hapticd::reference::falcon {

inline constexpr const char* kSerial = "FHS00001";

// Writes the test's firmware image (any image of a plausible size loads) and returns its path.
std::string image_file();

// hapticd opens the Falcon as it configures: the device is plugged in (the kernel has
// enumerated it) before, as a user's is.
bool plugged_in(const RawUsbFtdi& d);

// The settings that point config/falcon.yaml at the reference: its firmware image and serial.
std::vector<std::string> reference_sets();

// For a run that failed: the last `ticks` records of its tick log, on stderr.
void print_log_end(const std::string& log, int ticks);

// The test's hand on the reference's grip: a force it sets, and a spring to a line or a point
// it runs from its own thread (the reference has no gravity and no hand of its own).
class Hand {
 public:
  explicit Hand(RawUsbFtdi& d);
  ~Hand();
  Hand(const Hand&) = delete;
  Hand& operator=(const Hand&) = delete;
  // A push `f` (N) plus a spring (k N/m, damped) toward `centre` across the push's direction.
  void set(const Vec3& f, const Vec3& centre, double k, double b = 5.0);

 private:
  void run();
  RawUsbFtdi& d_;
  std::mutex m_;
  Vec3 f_{}, centre_{0, 0, 0.11};
  double k_ = 0, b_ = 5.0;
  std::atomic<bool> stop_{false};
  std::thread t_;
};

// Once hapticd asks for homing: the grip pulled out along +z until every arm is homed, then
// brought back to the middle of the box, where the walls will be armed.
bool home(RawUsbFtdi& d, Hand& hand);

// Until hapticd has enabled output (the LED green) or ended.
bool output_on(RawUsbFtdi& d, pid_t pid);

}  // namespace hapticd::reference::falcon
