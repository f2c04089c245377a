// How the driver and its loopback peer talk over a SOCK_SEQPACKET socketpair
// (io::seqpacket_pair(): one packet is one message, boundaries kept). The messages carry
// exactly what hidapi carries, so the driver's protocol code runs unchanged over either:
//
//   byte 0   type                 then
//   0x01     input report         the report as hid_read returns it (device -> host)
//   0x02     output report        the report as hid_write takes it: id first, 0 if unnumbered
//   0x03     set feature          the report, id first (host -> device); answered by 0x83
//   0x04     get feature          [report id][max length, u16 little-endian]; answered by 0x84
//   0x05     get descriptor       nothing; answered by 0x85
//   0x83     set feature reply    [status]
//   0x84     get feature reply    [status][the report, id first]
//   0x85     descriptor reply     [status][the report descriptor]
//
// status is 0 for success, else the errno the host's call would see (EPIPE: the device
// stalled the request). Output reports are not answered: the device answers the way firmware
// does, with input reports. Pure: no OS headers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "drivers/hid/report_descriptor.h"

namespace hapticd::drivers::hid {

enum class FrameType : std::uint8_t {
  kInputReport = 0x01,
  kOutputReport = 0x02,
  kSetFeature = 0x03,
  kGetFeature = 0x04,
  kGetDescriptor = 0x05,
  kSetFeatureReply = 0x83,
  kGetFeatureReply = 0x84,
  kDescriptorReply = 0x85,
};

// The longest message: a descriptor reply with the largest descriptor.
inline constexpr std::size_t kMaxFrame = 2 + kMaxDescriptorSize;

struct FrameView {
  FrameType type;
  std::span<const std::uint8_t> payload;  // everything after the type byte
};

// RT-safe. Nothing for an empty message or an unknown type.
std::optional<FrameView> parse_frame(std::span<const std::uint8_t> message) noexcept;

// RT-safe. Writes [type][payload] into `out` (which must hold payload.size() + 1 bytes);
// returns the message length.
std::size_t write_frame(FrameType type, std::span<const std::uint8_t> payload,
                        std::span<std::uint8_t> out) noexcept;

// Not RT-safe: the request and reply messages of configuration time.
std::vector<std::uint8_t> frame(FrameType type, std::span<const std::uint8_t> payload);
std::vector<std::uint8_t> get_feature_request(std::uint8_t report_id, std::uint16_t max_length);
std::vector<std::uint8_t> reply(FrameType type, std::uint8_t status,
                                std::span<const std::uint8_t> payload);

}  // namespace hapticd::drivers::hid
