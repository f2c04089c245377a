#include "drivers/gpio/gpiod_lines_common.h"

#include <fcntl.h>

#include <cerrno>
#include <cstring>

#include "drivers/device.h"

namespace hapticd::drivers::gpio::gpiod_common {

std::vector<InputLine> input_lines(const LineOffsets& lines) {
  std::vector<InputLine> inputs = {{Line::kA, lines.a}, {Line::kB, lines.b}};
  if (lines.index) inputs.push_back({Line::kIndex, *lines.index});
  if (lines.fault) inputs.push_back({Line::kFault, *lines.fault});
  return inputs;
}

std::string why(int err) {
  if (err == EBUSY) return "busy (another process or a kernel driver holds it: see gpioinfo)";
  if (err == EACCES || err == EPERM) {
    return std::string(std::strerror(err)) +
           " (`hapticd udev-rules` writes the rules that give group hapticd access)";
  }
  return std::strerror(err);
}

int make_nonblocking(int fd) noexcept {
  const int flags = fcntl(fd, F_GETFL);
  if (flags < 0 || fcntl(fd, F_SETFL, flags | O_NONBLOCK) != 0) return errno;
  return 0;
}

std::uint8_t read_levels(std::span<const InputLine> inputs,
                         const std::function<int(std::size_t)>& value) {
  std::uint8_t levels = 0;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const int v = value(i);
    if (v < 0) {
      throw DeviceError("gpio: cannot read line " + std::to_string(inputs[i].offset) + ": " +
                        why(errno));
    }
    if (v != 0) levels |= static_cast<std::uint8_t>(1u << static_cast<unsigned>(inputs[i].role));
  }
  return levels;
}

std::string describe(const std::string& chip, std::span<const InputLine> inputs,
                     unsigned direction) {
  std::string lines;
  for (const InputLine& in : inputs) lines += std::to_string(in.offset) + ",";
  return chip + " lines " + lines + "dir " + std::to_string(direction);
}

}  // namespace hapticd::drivers::gpio::gpiod_common
