// A simulated GPIO chip (gpio-sim, configured through configfs) inside the kernel test
// machine. To the GPIO character device and libgpiod it is a real gpiochip; the fixture plays
// the world outside it: set_pull() drives an input line as a pull resistor would, and a line
// requested for both-edge events sees each change as an edge with a kernel timestamp (the
// simulator raises a real interrupt). value() reads what a line is at, including what a
// consumer drives on an output line.
#pragma once

#include <string>
#include <vector>

namespace hapticd::kernel_test {

class GpioSimChip {
 public:
  // A chip with NUM_LINES lines (named LINE_NAMES[i] where given), all pulled down.
  explicit GpioSimChip(unsigned num_lines, std::string label = "hapticd-gpio-sim",
                       std::vector<std::string> line_names = {}, std::string name = "hapticd");
  ~GpioSimChip();  // takes the chip down and removes its configfs tree
  GpioSimChip(const GpioSimChip&) = delete;
  GpioSimChip& operator=(const GpioSimChip&) = delete;

  const std::string& chip_name() const noexcept { return chip_name_; }  // "gpiochipN"
  std::string dev_path() const { return "/dev/" + chip_name_; }         // for gpiod_chip_open
  const std::string& label() const noexcept { return label_; }
  unsigned num_lines() const noexcept { return num_lines_; }

  void set_pull(unsigned line, bool up);  // "pull-up" or "pull-down"
  bool value(unsigned line) const;

 private:
  std::string line_attr(unsigned line, const char* attr) const;
  void remove_configfs_tree() noexcept;

  unsigned num_lines_;
  std::string label_;
  std::vector<std::string> line_names_;
  std::string root_;   // /sys/kernel/config/gpio-sim/<name>
  std::string sysfs_;  // /sys/devices/platform/gpio-sim.N/gpiochipM
  std::string chip_name_;
};

}  // namespace hapticd::kernel_test
