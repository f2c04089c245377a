#include "gpio_sim_chip.h"

#include <utility>

#include "sysfs.h"

namespace hapticd::kernel_test {

GpioSimChip::GpioSimChip(unsigned num_lines, std::string label, std::vector<std::string> line_names,
                         std::string name)
    : num_lines_(num_lines),
      label_(std::move(label)),
      line_names_(std::move(line_names)),
      root_("/sys/kernel/config/gpio-sim/" + name) {
  require_path("/sys/kernel/config/gpio-sim", "gpio-sim (built by tools/kernel-vm/setup)");
  if (line_names_.size() > num_lines_) throw KernelFacilityError("more line names than lines");
  try {
    make_dir(root_);
    make_dir(root_ + "/bank0");
    write_text(root_ + "/bank0/num_lines", std::to_string(num_lines_));
    write_text(root_ + "/bank0/label", label_);
    for (std::size_t i = 0; i < line_names_.size(); ++i) {
      const std::string line = root_ + "/bank0/line" + std::to_string(i);
      make_dir(line);
      write_text(line + "/name", line_names_[i]);
    }
    write_text(root_ + "/live", "1");
    chip_name_ = read_text(root_ + "/bank0/chip_name");
    sysfs_ = "/sys/devices/platform/" + read_text(root_ + "/dev_name") + "/" + chip_name_;
    require_path(dev_path(), "the GPIO character device of " + chip_name_);
  } catch (...) {
    remove_configfs_tree();
    throw;
  }
}

GpioSimChip::~GpioSimChip() { remove_configfs_tree(); }

void GpioSimChip::remove_configfs_tree() noexcept {
  if (!path_exists(root_)) return;
  try {
    if (read_text(root_ + "/live") == "1") write_text(root_ + "/live", "0");
  } catch (const KernelFacilityError&) {
    // configfs refuses the rmdirs below then; a later fixture reports the leftover.
  }
  for (std::size_t i = 0; i < line_names_.size(); ++i) {
    remove_dir(root_ + "/bank0/line" + std::to_string(i));
  }
  remove_dir(root_ + "/bank0");
  remove_dir(root_);
}

std::string GpioSimChip::line_attr(unsigned line, const char* attr) const {
  if (line >= num_lines_) {
    throw KernelFacilityError("line " + std::to_string(line) + " of a " +
                              std::to_string(num_lines_) + "-line chip");
  }
  return sysfs_ + "/sim_gpio" + std::to_string(line) + "/" + attr;
}

void GpioSimChip::set_pull(unsigned line, bool up) {
  write_text(line_attr(line, "pull"), up ? "pull-up" : "pull-down");
}

bool GpioSimChip::value(unsigned line) const { return read_text(line_attr(line, "value")) == "1"; }

}  // namespace hapticd::kernel_test
