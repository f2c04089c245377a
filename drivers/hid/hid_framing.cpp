#include "drivers/hid/hid_framing.h"

#include <cstring>

namespace hapticd::drivers::hid {

std::optional<FrameView> parse_frame(std::span<const std::uint8_t> message) noexcept {
  if (message.empty()) return std::nullopt;
  switch (static_cast<FrameType>(message[0])) {
    case FrameType::kInputReport:
    case FrameType::kOutputReport:
    case FrameType::kSetFeature:
    case FrameType::kGetFeature:
    case FrameType::kGetDescriptor:
    case FrameType::kSetFeatureReply:
    case FrameType::kGetFeatureReply:
    case FrameType::kDescriptorReply:
      return FrameView{static_cast<FrameType>(message[0]), message.subspan(1)};
  }
  return std::nullopt;
}

std::size_t write_frame(FrameType type, std::span<const std::uint8_t> payload,
                        std::span<std::uint8_t> out) noexcept {
  out[0] = static_cast<std::uint8_t>(type);
  if (!payload.empty()) std::memcpy(out.data() + 1, payload.data(), payload.size());
  return payload.size() + 1;
}

std::vector<std::uint8_t> frame(FrameType type, std::span<const std::uint8_t> payload) {
  std::vector<std::uint8_t> m(payload.size() + 1);
  write_frame(type, payload, m);
  return m;
}

std::vector<std::uint8_t> get_feature_request(std::uint8_t report_id, std::uint16_t max_length) {
  const std::uint8_t p[3] = {report_id, static_cast<std::uint8_t>(max_length & 0xFF),
                             static_cast<std::uint8_t>(max_length >> 8)};
  return frame(FrameType::kGetFeature, p);
}

std::vector<std::uint8_t> reply(FrameType type, std::uint8_t status,
                                std::span<const std::uint8_t> payload) {
  std::vector<std::uint8_t> m(payload.size() + 2);
  m[0] = static_cast<std::uint8_t>(type);
  m[1] = status;
  if (!payload.empty()) std::memcpy(m.data() + 2, payload.data(), payload.size());
  return m;
}

}  // namespace hapticd::drivers::hid
