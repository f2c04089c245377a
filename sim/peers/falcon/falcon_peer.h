// The Falcon driver's simulated device (docs/drivers/falcon.md): a Novint Falcon on the other end
// of the driver's loopback SOCK_SEQPACKET socketpair, one message each (the codec's LoopbackTag):
// host to device [kTagControl, request, value_lo, value_hi] (an FTDI vendor request) and
// [kTagBulkOut, bytes...] (a bulk OUT transfer); device to host [kTagBulkIn, bytes...], one bulk IN
// transfer as an FT232 sends it (modem status 0x31 0x60 at the head of each 64-byte USB packet).
// It sends one only when it has data: the chip's status-only packets carry nothing a host reads,
// so a host's read finds nothing until its timeout instead.
//
// Behind the chip: the bootloader (ft232_bootloader.h) that firmware_loader.cpp loads, then the
// firmware (falcon_firmware.h) that takes each command packet, steps the delta of
// device.kinematics and answers with a state packet. It needs no device.falcon section: any
// configuration whose device.kinematics has three joints (delta) is a Falcon.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "config/config.h"
#include "drivers/falcon/falcon_protocol.h"
#include "drivers/io/unique_fd.h"
#include "sim/peers/falcon/falcon_firmware.h"
#include "sim/peers/falcon/ft232_bootloader.h"
#include "sim/peers/loopback_peer.h"
#include "sim/peers/peer_state.h"
#include "sim/sim_axis.h"

namespace hapticd::sim::falcon {

struct FalconPeerOptions {
  // The bootloader of the first DTR pulse ignores the first check: the first load fails.
  bool fail_first_load = false;
  // Packets with the homing bit until the simulated person has homed the grip.
  int homing_packets = 20;
};

class FalconPeer final : public LoopbackPeer {
 public:
  // Not RT-safe. Throws std::invalid_argument for a plant that cannot be simulated or a
  // device.kinematics of other than three joints.
  FalconPeer(const config::Config& cfg, io::UniqueFd fd, FalconPeerOptions options = {});

  void service() override;
  int fd() const noexcept override { return fd_.get(); }
  // While IN data waits for room on the socket: 1 ms; otherwise only on input.
  int service_interval_ms() const noexcept override { return pending_.empty() ? -1 : 1; }
  // The largest |joint torque| (N m) and whether the amplifier is on (any nonzero count).
  double applied_force() const noexcept override { return felt_.force(); }
  bool output_on() const noexcept override { return felt_.on(); }
  // plant() is an unused axis of its own; joint_plant() is the delta.
  const Plant& plant() const noexcept override { return axis_.plant(); }
  const JointPlant* joint_plant() const noexcept override { return &firmware_.mechanism().plant(); }
  // kStopAnswering: nothing more comes back (a hung device; the motors keep what they were
  // last sent); kTransportFault: unplugged (the socket shut: the host reads end-of-file).
  // kDeviceFault, kSkipSequence: false (the Falcon reports no fault and numbers nothing).
  bool inject(PeerFault fault) noexcept override;

  // Any thread. The next state packet goes out with a byte out of the nibble range (once).
  void corrupt_next_packet() noexcept { corrupt_next_.store(true); }

  // Any thread: what the device did so far.
  std::uint8_t leds() const noexcept { return leds_.load(); }  // the last command's Led bits
  bool homed() const noexcept { return homed_.load(); }
  bool firmware_running() const noexcept { return running_.load(); }
  // Command packets the firmware took (each a period of the plant), state packets it sent.
  std::uint64_t packets_taken() const noexcept { return taken_.load(); }
  std::uint64_t packets_answered() const noexcept { return answered_.load(); }
  int loads_completed() const noexcept { return loads_.load(); }
  int resets() const noexcept { return resets_.load(); }  // DTR pulses
  std::uint64_t bad_messages() const noexcept { return bad_messages_.load(); }

  // The peer's thread (or after it stopped): the chip and the firmware.
  const Ft232Bootloader& chip() const noexcept { return chip_; }
  const FalconFirmware& firmware() const noexcept { return firmware_; }

 private:
  void handle(std::span<const unsigned char> message);
  void control(std::uint8_t request, std::uint16_t value);
  void bulk_out(std::span<const unsigned char> data);
  void flush();
  void publish() noexcept;

  SimAxis axis_;
  Ft232Bootloader chip_;
  FalconFirmware firmware_;
  io::UniqueFd fd_;
  std::vector<unsigned char> pending_;  // data bytes for the host, not yet sent
  std::vector<drivers::falcon::Packet> answers_;
  std::atomic<bool> shut_{false};
  std::atomic<bool> corrupt_next_{false};
  FaultFlags<PeerFault> faults_{PeerFault::kStopAnswering, PeerFault::kTransportFault};
  FeltOutput felt_;
  std::atomic<std::uint8_t> leds_{0};
  std::atomic<bool> homed_{false};
  std::atomic<bool> running_{false};
  std::atomic<std::uint64_t> taken_{0};
  std::atomic<std::uint64_t> answered_{0};
  std::atomic<int> loads_{0};
  std::atomic<int> resets_{0};
  std::atomic<std::uint64_t> bad_messages_{0};
};

// The peer of the driver's registration (falcon_peer_entry.h), with the default options.
std::unique_ptr<LoopbackPeer> make_loopback_peer(const config::Config& cfg, io::UniqueFd fd);

}  // namespace hapticd::sim::falcon
