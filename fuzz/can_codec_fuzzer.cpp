// libFuzzer target for the CAN driver's codecs (drivers/can/): every 11 bytes of the input are
// one frame (id and flags in two bytes, a raw length that may exceed 8, eight data bytes)
// decoded by every CiA 301, CiA 402 and ODrive CAN Simple decoder, and the whole input is one
// message through a socketpair into CanSocket::receive, as a lying peer would send it.
// Invariants: decoding never crashes; what decodes re-encodes to the same bytes; sizes, states
// and texts are what their types promise; a message that is not one struct can_frame is
// reported as malformed, never as a frame.
#include <unistd.h>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "drivers/can/can_socket.h"
#include "drivers/can/canopen.h"
#include "drivers/can/cia402.h"
#include "drivers/can/odrive_protocol.h"
#include "drivers/io/unique_fd.h"
#include "support/check.h"

namespace {

namespace can = hapticd::drivers::can;
namespace canopen = can::canopen;
namespace cia402 = can::cia402;
namespace odrive = can::odrive;
using hapticd::fuzz::require;

can::CanFrame frame_of(const std::uint8_t* p) {
  can::CanFrame f;
  f.id = static_cast<std::uint32_t>(p[0] | (p[1] << 8)) & can::kSffMask;
  f.rtr = (p[1] & 0x80) != 0;
  f.extended = (p[1] & 0x40) != 0;
  f.len = p[2];
  std::memcpy(f.data.data(), p + 3, 8);
  return f;
}

bool same_payload(const can::CanFrame& a, const can::CanFrame& b, int n) {
  return a.len == b.len && std::memcmp(a.data.data(), b.data.data(), n) == 0;
}

void check_canopen(const can::CanFrame& f) {
  const canopen::SdoAddress at{can::get_u16(f, 1), f.data[3]};
  const canopen::SdoReply r = canopen::decode_sdo_reply(f, at);
  if (r.kind == canopen::SdoReply::Kind::kUploadValue) {
    require(r.size >= 1 && r.size <= 4, "SDO upload size in 1..4");
    require(r.size == 4 || r.value < (1u << (8 * r.size)), "SDO value fits its size");
  }
  if (r.kind == canopen::SdoReply::Kind::kMalformed) require(*r.problem != '\0', "named problem");
  if (r.kind == canopen::SdoReply::Kind::kAbort) {
    require(!canopen::describe_sdo_abort(r.abort_code).empty(), "abort text");
  }
  const canopen::SdoRequest q = canopen::decode_sdo_request(f);
  if (q.kind == canopen::SdoRequest::Kind::kDownload) {
    require(q.size >= 1 && q.size <= 4, "SDO download size in 1..4");
    const can::CanFrame again = canopen::sdo_download_request(0, q.at, q.value, q.size);
    require(canopen::decode_sdo_request(again).value == q.value, "SDO download round trip");
  }
  if (const auto s = canopen::decode_heartbeat(f)) {
    require(canopen::decode_heartbeat(canopen::heartbeat_frame(0, *s)) == s,
            "heartbeat round trip");
    require(!canopen::to_string(*s).empty(), "NMT state name");
  }
  const auto e = canopen::decode_emcy(f);
  require(e.has_value() == (!f.rtr && f.len >= 3), "EMCY decodes iff 3 bytes or more");
  if (e) require(canopen::describe_emcy_code(e->code).rfind("0x", 0) == 0, "EMCY text");
  if (const auto t = canopen::decode_tpdo1(f)) {
    require(same_payload(canopen::tpdo1_frame(0, t->statusword, t->position), f, 6),
            "TPDO1 round trip");
  }
  if (const auto r1 = canopen::decode_rpdo1(f)) {
    require(same_payload(canopen::rpdo1_frame(0, r1->controlword, r1->target_torque), f, 4),
            "RPDO1 round trip");
  }
}

void check_cia402(const can::CanFrame& f) {
  const std::uint16_t sw = can::get_u16(f, 0);
  const cia402::PowerState s = cia402::decode_statusword(sw);
  require(cia402::decode_statusword(cia402::encode_statusword(s)) == s, "statusword round trip");
  require(!cia402::describe_statusword(sw).empty(), "statusword text");
  const cia402::PowerState next =
      cia402::apply_controlword(s, can::get_u16(f, 2), can::get_u16(f, 4));
  require(static_cast<int>(next) <= static_cast<int>(cia402::PowerState::kFault), "a state");
  if (const auto cw = cia402::step_towards_enabled(s)) {
    require(cia402::apply_controlword(s, *cw, 0) != s, "each step moves the state machine");
  }
}

void check_odrive(const can::CanFrame& f) {
  for (const odrive::Firmware fw : {odrive::Firmware::k05, odrive::Firmware::k06}) {
    require(odrive::describe_axis_error(fw, can::get_u32(f, 0)).rfind("0x", 0) == 0, "axis error");
  }
  require(!odrive::axis_state_name(f.data[4]).empty(), "axis state name");
  if (const auto h = odrive::decode_heartbeat(f)) {
    const auto again = odrive::decode_heartbeat(odrive::heartbeat(0, *h));
    require(again && again->axis_error == h->axis_error && again->axis_state == h->axis_state,
            "heartbeat round trip");
  }
  if (const auto e = odrive::decode_encoder_estimates(f)) {
    require(same_payload(odrive::encoder_estimates(0, *e), f, 8), "estimates round trip (bits)");
  }
  if (const auto v = odrive::decode_version(f)) odrive::firmware_of(*v);
  if (const auto r = odrive::decode_rx_sdo(f)) {
    require(odrive::decode_rx_sdo(odrive::rx_sdo(0, r->write, r->endpoint, r->value))->value ==
                r->value,
            "RxSdo round trip");
  }
  if (const auto t = odrive::decode_tx_sdo(f)) {
    const auto again = odrive::decode_tx_sdo(odrive::tx_sdo(0, *t));
    require(again && again->endpoint == t->endpoint && again->value == t->value,
            "TxSdo round trip");
  }
}

// The whole input as one message from a peer that lies.
void check_socket(const std::uint8_t* data, std::size_t size) {
  static auto pair = hapticd::io::seqpacket_pair();
  static can::CanSocket reader = can::CanSocket::adopt(std::move(pair.first), "fuzz");
  if (size == 0 || size > 4096) return;
  if (::write(pair.second.get(), data, size) != static_cast<ssize_t>(size)) return;
  can::CanSocket::Received rx;
  int error = 0;
  const can::CanSocket::Io r = reader.receive(rx, error);
  if (size != 16)
    require(r == can::CanSocket::Io::kMalformed, "a message of another size is malformed");
  if (r == can::CanSocket::Io::kDone && !rx.is_event) require(rx.frame.len <= 8, "DLC at most 8");
  require(r != can::CanSocket::Io::kFailed, "a malformed message is no socket failure");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  for (std::size_t at = 0; at + 11 <= size; at += 11) {
    const can::CanFrame f = frame_of(data + at);
    check_canopen(f);
    check_cia402(f);
    check_odrive(f);
  }
  check_socket(data, size);
  return 0;
}
