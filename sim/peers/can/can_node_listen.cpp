#include "sim/peers/can/can_node_listen.h"

#include <spdlog/spdlog.h>

#include <cerrno>
#include <chrono>
#include <vector>

#include "base/errno_text.h"
#include "base/hex.h"
#include "drivers/can/can_socket.h"
#include "drivers/can/canopen.h"
#include "drivers/can/odrive_protocol.h"
#include "drivers/device.h"

namespace hapticd::sim {
namespace {

namespace can = drivers::can;
namespace canopen = drivers::can::canopen;
namespace odrive = drivers::can::odrive;

// What a CANopen node sends under its own id (CiA 301's predefined connection set): EMCY,
// TPDO1..4, SDO replies, heartbeat and boot-up. RPDOs and SDO requests are a master's.
constexpr std::uint32_t kCiaNodeBases[] = {
    canopen::kEmcyBase,  canopen::kTpdo1Base,    canopen::kTpdo2Base, 0x380, 0x480,
    canopen::kSdoTxBase, canopen::kHeartbeatBase};

// What an ODrive sends as data frames: its heartbeat, and the answers to a master's remote
// requests (Get_Error, Get_Encoder_Estimates) and endpoint reads (TxSdo).
bool odrive_sends(std::uint8_t command) {
  return command == odrive::kHeartbeat || command == odrive::kGetError ||
         command == odrive::kTxSdo || command == odrive::kGetEncoderEstimates;
}

}  // namespace

bool sent_by_node(const can::CanFrame& f, const can::CanSettings& s) {
  if (f.rtr || f.extended) return false;  // a remote request asks; the node answers with data
  if (s.profile == can::Profile::kOdrive) {
    return odrive::node_of(f.id) == s.nodes.front().node_id &&
           odrive_sends(odrive::command_of(f.id));
  }
  for (std::uint32_t base : kCiaNodeBases) {
    if (f.id == base + s.nodes.front().node_id) return true;
  }
  return false;
}

std::string describe_node_frame(const can::CanFrame& f, const can::CanSettings& s) {
  const std::string node = "node " + std::to_string(s.nodes.front().node_id);
  std::string what;
  if (s.profile == can::Profile::kOdrive) {
    what = odrive::command_of(f.id) == odrive::kHeartbeat
               ? "the heartbeat of ODrive " + node
               : "an answer of ODrive " + node + " (command " +
                     base::hex(odrive::command_of(f.id), 3) + ")";
  } else if (f.id == canopen::kHeartbeatBase + s.nodes.front().node_id) {
    const auto state = canopen::decode_heartbeat(f);
    what = "the heartbeat of " + node +
           (state ? " (" + std::string(canopen::to_string(*state)) + ")" : "");
  } else if (f.id == canopen::kSdoTxBase + s.nodes.front().node_id) {
    what = "an SDO reply of " + node;
  } else if (f.id == canopen::kEmcyBase + s.nodes.front().node_id) {
    what = "an EMCY of " + node;
  } else {
    what = "a TPDO of " + node;
  }
  return base::hex(f.id, 3) + ", " + what;
}

can::CanFrame node_probe(const can::CanSettings& s) {
  if (s.profile == can::Profile::kOdrive) {
    return odrive::request(s.nodes.front().node_id, odrive::kGetEncoderEstimates, 8);
  }
  return canopen::sdo_upload_request(s.nodes.front().node_id,
                                     {0x1000, 0});  // device type: mandatory
}

std::optional<can::CanFrame> listen_for_node(const can::CanSettings& s,
                                             const std::string& interface, double seconds) {
  std::vector<can::IdFilter> filters;
  if (s.profile == can::Profile::kOdrive) {
    filters.push_back(
        {odrive::frame_id(s.nodes.front().node_id, 0), 0x7E0});  // the node's 32 command ids
  } else {
    for (std::uint32_t base : kCiaNodeBases) filters.push_back({base + s.nodes.front().node_id});
  }
  can::CanSocket socket = can::CanSocket::open_interface(interface, filters, false);
  int error = 0;
  if (socket.send(node_probe(s), error) == can::CanSocket::Io::kFailed) {
    throw DeviceError("peer: cannot ask node " + std::to_string(s.nodes.front().node_id) + " on " +
                      interface + ": " + base::errno_text(error));
  }
  using Clock = std::chrono::steady_clock;
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  for (auto now = Clock::now(); now < end; now = Clock::now()) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(end - now).count();
    if (!socket.wait_readable(static_cast<int>(left))) continue;
    can::CanSocket::Received r;
    while (socket.receive(r, error) == can::CanSocket::Io::kDone) {
      if (!r.is_event && sent_by_node(r.frame, s)) return r.frame;
    }
  }
  return std::nullopt;
}

void check_can_node_free(const config::Config& cfg, const std::string& interface, double seconds) {
  const auto& all = can::can_settings(cfg);
  for (std::size_t i = 0; i < all.nodes.size(); ++i) {
    const can::CanSettings s = can::single_node(all, i);
    const std::uint8_t id = s.nodes.front().node_id;
    spdlog::info("peer: listening {} s on {} for a node {} already there", seconds, interface, id);
    if (const auto heard = listen_for_node(s, interface, seconds)) {
      const std::string key = all.nodes.size() > 1
                                  ? "device.can.nodes[" + std::to_string(i) + "].node_id"
                                  : std::string("device.can.node_id");
      throw DeviceError("peer: a node already answers at node id " + std::to_string(id) + " on " +
                        interface + " (heard " + describe_node_frame(*heard, s) +
                        "): a simulated drive there would answer beside it. Stop that node, or "
                        "give the peer another " +
                        key);
    }
  }
}

}  // namespace hapticd::sim
