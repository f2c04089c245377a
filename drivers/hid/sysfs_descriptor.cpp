#include "drivers/hid/sysfs_descriptor.h"

#include <dirent.h>

#include <fstream>
#include <iterator>

#include "drivers/hid/report_descriptor.h"

namespace hapticd::drivers::hid {
namespace {

// The report_descriptor file under a USB interface's HID device ("0003:1209:FFB0.0001").
std::string interface_descriptor_file(const std::string& interface) {
  const std::string dir = "/sys/bus/usb/devices/" + interface;
  DIR* d = opendir(dir.c_str());
  if (d == nullptr) return "";
  std::string file;
  for (dirent* e = readdir(d); e != nullptr && file.empty(); e = readdir(d)) {
    const std::string name = e->d_name;
    if (name.size() > 10 && name[4] == ':') file = dir + "/" + name + "/report_descriptor";
  }
  closedir(d);
  return file;
}

}  // namespace

std::optional<std::vector<std::uint8_t>> kernel_report_descriptor(const std::string& path,
                                                                  bool libusb_path) {
  const std::string file = libusb_path ? interface_descriptor_file(path)
                                       : "/sys/class/hidraw/" + path.substr(path.rfind('/') + 1) +
                                             "/device/report_descriptor";
  if (file.empty()) return std::nullopt;
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
  if (bytes.empty() || bytes.size() > kMaxDescriptorSize) return std::nullopt;
  return bytes;
}

}  // namespace hapticd::drivers::hid
