// A simulated CiA 402 servo drive in cyclic synchronous torque (docs/drivers/can.md): NMT, an SDO
// server for the objects hapticd uses (with CiA 301 abort codes for everything else), the
// power state machine, PDOs packed and unpacked through their mapping objects (so a wrong
// mapping shows up as a wrong frame, as on a real drive), and at each SYNC the plant stepped
// one period, the RPDO applied and the TPDOs sent. It produces its heartbeat, sends EMCY on a
// fault, and - in realtime - watches hapticd's heartbeat (0x1016) and the SYNC cycle (0x1006:
// 20 cycles, or the heartbeat consumer time if longer), reacting as 0x6007 says when the master
// goes silent: a drive that fails safe when the process is killed. Rated torque 0x6076:
// kRatedTorqueMilliNm.
#pragma once

#include <cstdint>
#include <map>
#include <utility>

#include "drivers/can/cia402.h"
#include "sim/peers/can/can_peer_base.h"

namespace hapticd::sim {

class Cia402Peer final : public CanPeerBase {
 public:
  static constexpr std::uint32_t kRatedTorqueMilliNm = 500;
  // The EMCY a commanded fault sends: continuous over-current.
  static constexpr std::uint16_t kFaultEmcyCode = 0x2310;

  // `joint`: the joint of a mechanism it moves with the other drives of its bus (can_bus_peer.h).
  Cia402Peer(const config::Config& cfg, drivers::can::CanSocket socket, bool realtime,
             const SharedJoint& joint = {});

  // Any thread, for tests: the power state and NMT state right now.
  drivers::can::cia402::PowerState power_state() const noexcept { return power_.load(); }
  // Any thread, for tests: 0x6064 counts from `counts` at the plant's zero, as a drive that
  // keeps an offset (a homing, a multi-turn count). 0x6064 is a signed 32-bit count: it
  // rolls over past 2^31 - 1 to -2^31 and back, as a real drive's does.
  void offset_position(std::int64_t counts) noexcept { position_offset_.store(counts); }
  // Any thread, for tests: the DC link charges `ms` from now (negative: never, no mains);
  // until then the drive stays in switch on disabled, its statusword's bit 4 (voltage
  // enabled) at 0, refusing the shutdown command, as drives do after mains on.
  void charge_dc_link_after(int ms) noexcept;

 protected:
  void handle(const drivers::can::CanFrame& f) override;
  void on_clock(std::int64_t now_ns) override;
  void apply_device_fault() override;
  void on_bus_lost() override;

 private:
  using Key = std::pair<std::uint16_t, std::uint8_t>;
  void on_nmt(drivers::can::canopen::NmtCommand c);
  void on_sdo(const drivers::can::CanFrame& f);
  void on_sync();
  void on_rpdo(const drivers::can::CanFrame& f);
  // The abort code for a write of `value` to `at`, 0 when it is accepted (and stored).
  std::uint32_t write_object(drivers::can::canopen::SdoAddress at, std::uint32_t value);
  bool read_object(drivers::can::canopen::SdoAddress at, std::uint32_t& value, std::uint8_t& size);
  void set_controlword(std::uint16_t cw);
  void set_power(drivers::can::cia402::PowerState s);
  void enter_fault(std::uint16_t emcy_code, std::uint8_t error_register);
  void lose_master(std::uint16_t emcy_code);
  std::int32_t mapped_value(std::uint16_t index) noexcept;
  void send_tpdo(std::uint16_t comm, std::uint16_t map);
  void heartbeat();
  std::int32_t position_units() noexcept;
  std::uint32_t object(std::uint16_t index, std::uint8_t sub) const;

  const std::uint8_t node_;
  std::map<Key, std::uint32_t> od_;  // the writable objects, with factory defaults
  drivers::can::canopen::NmtState nmt_ = drivers::can::canopen::NmtState::kPreOperational;
  std::atomic<drivers::can::cia402::PowerState> power_{
      drivers::can::cia402::PowerState::kSwitchOnDisabled};
  std::uint16_t controlword_ = 0;
  std::int16_t target_torque_ = 0;
  std::uint16_t error_code_ = 0;
  bool pending_rpdo_ = false;
  std::uint16_t pending_cw_ = 0;
  std::int16_t pending_torque_ = 0;
  bool synced_ = false;
  std::uint64_t syncs_ = 0;
  std::int64_t last_heartbeat_ns_ = 0;
  std::int64_t last_sync_ns_ = 0;
  std::int64_t last_master_heartbeat_ns_ = 0;  // 0: none seen yet (not watched)
  std::atomic<std::int64_t> position_offset_{0};
  std::atomic<std::int64_t> dc_link_charged_ns_{0};  // CLOCK_MONOTONIC; 0: from the start
};

}  // namespace hapticd::sim
