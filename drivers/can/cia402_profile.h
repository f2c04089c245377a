// CiA 402 drives in cyclic synchronous torque (docs/drivers/can.md), driven over CANopen: one
// Cia402Node per node of device.can.nodes, and Cia402Profile driving them all on one bus, with
// one SYNC per tick for every node. What follows is each node's sequence.
//
// configure: NMT pre-operational, device type 0x1000 checked for profile 402, the power stage
// switched off (controlword 0x00, "switch on disabled"), rated torque 0x6076 and the drive's
// own limit 0x6072 read (below max_torque refuses: the wall would give way early), mode 10 in
// 0x6060 (0x6061 polled until it shows it), 0x1006 communication cycle = T and 0x60C2
// interpolation period = T where the drive has them (a notice names what it lacks), 0x1017
// heartbeat producer, 0x6007 the drive's reaction to losing the master (unless
// comm_loss_reaction is none), PDOs mapped (each COB-ID read first, only its valid bit and id
// changed) or verified - every SDO write confirmed, an abort named with CiA 301's text.
// enable: target torque 0, 0x1006 again, 0x1016 heartbeat consumer (the drive's own watchdogs
// on hapticd), NMT start, then the power state machine walked to Operation enabled through the
// controlword, each step confirmed from the statusword within state_timeout_ms.
// Each tick: the device drains the TPDOs, EMCY, heartbeat and bus events; the tick's frames are
// every node's RPDO (controlword 0x0F, target torque in per mille of its rated torque) and then
// one SYNC, at which each drive samples its position and applies the torque: the force
// computed from the sample a tick reads acts from the next SYNC on - one sample of delay,
// declared as such.
// disable (once per enable, a fault's included): at the next SYNC slot one RPDO with zero
// torque and controlword 0x06 (shutdown: power stage off); the statusword read back by SDO (a
// drive still enabled is switched off by SDO); SYNC and hapticd's heartbeat kept going, one
// per period, until the drive's watchdogs on them (0x1006, 0x1016) are switched off, so a
// normal stop raises no EMCY (a drive not confirmed off keeps them); the statusword read again
// after the last SYNC; then NMT pre-operational.
// clear_fault: fault reset (0x80 edge), confirmed.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "base/joints.h"
#include "drivers/can/can_profile.h"
#include "drivers/can/canopen.h"
#include "drivers/can/cia402.h"
#include "drivers/can/periodic_sender.h"
#include "drivers/io/counter_unwrap.h"

namespace hapticd::drivers::can {

// One drive on the bus: its start-up over SDO, its power state machine, the frames it sends
// and the one it is sent each tick. The bus's own frames (SYNC, hapticd's heartbeat, the SYNC
// keeper of a stop) are Cia402Profile's.
class Cia402Node {
 public:
  Cia402Node(const CanSettings& settings, const CanNode& node, double sample_period_s,
             CanLink& link)
      : settings_(settings), node_(node), period_s_(sample_period_s), link_(link) {}

  // Not RT-safe. Identified, switched off, parameters written, PDOs mapped; its description.
  std::string configure();
  // Not RT-safe. Target torque 0, its watches on hapticd, NMT start, Operation enabled.
  void enable();
  // Not RT-safe, never throw: the stop's steps (Cia402Profile::disable orders them).
  CanFrame shutdown_frame() const noexcept;
  bool confirm_off() noexcept;
  void stop_keeping_alive() noexcept;
  void enter_pre_operational() noexcept;
  // Not RT-safe. The fault reset, confirmed.
  void clear_fault();
  const std::vector<std::string>& notices() const { return notices_; }
  std::uint8_t node_id() const noexcept { return node_.node_id; }

  // RT-safe: called every tick (the four below). Whether a frame is one this node sends.
  bool owns(const CanFrame& f) const noexcept;
  FrameMeaning on_frame(const CanSocket::Received& rx, bool active) noexcept;
  void sample(PositionSample& out) const noexcept;
  // The RPDO carrying `force`: controlword 0x0F, target torque in per mille of rated torque.
  CanFrame rpdo(double force) const noexcept;
  // Not RT-safe. The sentence for a fault this node reported; "" for the bus's.
  std::string describe(const CanFault& fault) const;

 private:
  // RT-safe: called every tick (on_frame's parts).
  FrameMeaning on_tpdo1(const CanSocket::Received& rx, bool active) noexcept;
  FrameMeaning on_emcy(const CanFrame& f) noexcept;
  FrameMeaning on_heartbeat(const CanFrame& f, bool active) noexcept;

  // SDO client (non-RT): expedited transfers, each answered within sdo_timeout_ms.
  std::uint32_t sdo_read(canopen::SdoAddress at, const char* name);
  void sdo_write(canopen::SdoAddress at, std::uint32_t value, std::uint8_t size, const char* name);
  // For an object a drive may lack: nothing / false when the drive says it has no such object
  // (abort 0x06020000 or 0x06090011); any other abort throws as above.
  std::optional<std::uint32_t> sdo_read_optional(canopen::SdoAddress at, const char* name);
  bool sdo_write_optional(canopen::SdoAddress at, std::uint32_t value, std::uint8_t size,
                          const char* name);
  canopen::SdoReply sdo_exchange(const CanFrame& request, canopen::SdoAddress at, const char* name,
                                 bool may_lack = false);
  // Frames that arrive while configuring or enabling: an EMCY ends it with a DeviceError. In
  // the stop (stopping_) it is counted: the stop's steps go on.
  void note_async(const CanFrame& f);
  std::string sdo_where(canopen::SdoAddress at, const char* name) const;

  void switch_off_and_identify();
  void check_torque_limit();
  void select_mode();
  void write_parameters();
  void write_cycle_objects();
  void map_pdos();
  std::string node_name() const;
  void walk_to_enabled();
  cia402::PowerState take_step(cia402::PowerState from, std::uint16_t cw, std::uint16_t& sw);
  cia402::PowerState read_state(std::uint16_t& statusword);
  std::string drive_error_text();

  const CanSettings& settings_;  // the bus's (the profile's, which outlives its nodes)
  const CanNode node_;
  const double period_s_;
  CanLink& link_;
  std::vector<std::string> notices_;  // configure's
  std::uint32_t rated_torque_mnm_ = 0;
  double permille_per_force_ = 0.0;  // per mille of rated torque per N (or N m) of axis force
  int max_permille_ = 0;             // max_torque in per mille
  bool stopping_ = false;            // in confirm_off or stop_keeping_alive
  bool has_cycle_period_ = false;    // 0x1006 exists (optional: CiA 301 requires it of SYNC
                                     // producers only)

  // RT state of the newest sample. 0x6064 is a signed 32-bit count that rolls over (a
  // multi-turn axis, a fine encoder, a drive's offset): unwrapped from the first TPDO1 after
  // configure on, across enables.
  std::uint16_t statusword_ = 0;
  io::CounterUnwrap position_{32, true};
  std::int32_t velocity_ = 0;
  std::int64_t sample_time_ns_ = 0;
};

// The drives of device.can.nodes on one bus, joint i being node i: ONE SYNC per tick for
// all of them (after every node's RPDO), hapticd's one heartbeat, and the lifecycle through
// every node (a fault of any node is the device's: the loop writes zero to every joint, and
// the stop switches every node off).
class Cia402Profile final : public CanProfile {
 public:
  Cia402Profile(const CanSettings& settings, double sample_period_s, int keeper_priority,
                CanLink& link);

  DeviceInfo configure() override;
  void enable() override;
  void disable(const CanFault& latched) noexcept override;
  void clear_fault() override;
  void close() noexcept override { keeper_.stop(); }
  std::vector<std::string> notices() const override;
  // RT-safe: called every tick (the three below).
  FrameMeaning on_frame(const CanSocket::Received& rx, bool active) noexcept override;
  void sample(std::size_t joint, PositionSample& out) const noexcept override;
  std::span<const CanFrame> tick_frames(std::span<const double> forces) noexcept override;
  std::string describe(const CanFault& fault, const std::string& bus) const override;

 private:
  const CanSettings settings_;
  const double period_s_;
  const int keeper_priority_;
  CanLink& link_;
  std::vector<Cia402Node> nodes_;  // built once, never resized (the RT path indexes it)
  std::uint32_t master_heartbeat_ticks_ = 0;
  std::uint32_t tick_ = 0;
  bool stopped_ = true;  // the stop went out since the last enable
  PeriodicSender keeper_;
  std::atomic<std::int64_t> last_sync_ns_{0};        // the RT thread's last SYNC (CLOCK_MONOTONIC)
  std::array<CanFrame, base::kMaxJoints + 2> tx_{};  // the tick's frames
};

}  // namespace hapticd::drivers::can
