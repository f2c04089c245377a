#include "drivers/gpio/gpiod_lines_common.h"

#include <fcntl.h>

#include <cerrno>
#include <cstring>

#include "drivers/device.h"

namespace hapticd::drivers::gpio::gpiod_common {

std::vector<InputLine> input_lines(std::span<const LineOffsets> joints) {
  std::vector<InputLine> inputs;
  for (const LineOffsets& lines : joints) {
    inputs.push_back({Line::kA, lines.a, lines.joint});
    inputs.push_back({Line::kB, lines.b, lines.joint});
    if (lines.index) inputs.push_back({Line::kIndex, *lines.index, lines.joint});
    if (lines.fault) inputs.push_back({Line::kFault, *lines.fault, lines.joint});
  }
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

void read_levels(std::span<const InputLine> inputs, const std::function<int(std::size_t)>& value,
                 std::span<std::uint8_t> levels) {
  for (const InputLine& in : inputs) levels[in.joint] = 0;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const int v = value(i);
    if (v < 0) {
      throw DeviceError("gpio: cannot read line " + std::to_string(inputs[i].offset) + ": " +
                        why(errno));
    }
    if (v != 0) {
      levels[inputs[i].joint] |=
          static_cast<std::uint8_t>(1u << static_cast<unsigned>(inputs[i].role));
    }
  }
}

std::string describe(const std::string& chip, std::span<const InputLine> inputs,
                     std::span<const DirectionLine> directions) {
  std::string out = chip;
  for (std::size_t d = 0; d < directions.size(); ++d) {
    std::string lines;
    for (const InputLine& in : inputs) {
      if (in.joint == directions[d].joint) lines += std::to_string(in.offset) + ",";
    }
    out +=
        (d == 0 ? " lines " : "; lines ") + lines + "dir " + std::to_string(directions[d].offset);
  }
  return out;
}

}  // namespace hapticd::drivers::gpio::gpiod_common
