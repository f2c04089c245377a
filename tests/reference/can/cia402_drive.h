// A CiA 402 servo drive in cyclic synchronous torque, written from the specifications and from
// the rules of the CANopenNode stack (github CANopenNode/CANopenNode, 301/), sharing nothing
// with drivers/:
//
// - CiA 301 and 301/CO_SDOserver.c: expedited SDO only; SDO in pre-operational and operational
//   only; an expedited download whose indicated size differs from the object's aborts
//   0x06070012 / 0x06070013; no object 0x06020000, no subindex 0x06090011, read-only
//   0x06010002; the abort codes of CO_ODinterface.c OD_getSDOabCode.
// - 301/CO_PDO.c (OD_write_14xx, OD_write_18xx, OD_write_PDO_mapping): a COB-ID with any of
//   bits 11-29 set, a changed CAN id while the PDO is valid, a restricted CAN id or a valid PDO
//   without mapping abort 0x06090030; transmission types 241-253 abort 0x06090030; a mapping
//   written while its PDO is valid, or a mapping entry while the count is not 0, aborts
//   0x06010000; over 8 entries or 64 bits 0x06040042; an object that cannot be mapped
//   0x06040041. A synchronous RPDO takes effect at the next SYNC; a synchronous TPDO is
//   sampled and sent at every n-th SYNC.
// - 301/CO_SYNC.c (CO_SYNC_process): in pre-operational and operational, once a SYNC has been
//   seen and 0x1006 > 0, 1.5 x 0x1006 without SYNC raises EMCY 0x8100 (CO_EMC_COMMUNICATION);
//   the next SYNC resets it (EMCY 0x0000).
// - 301/CO_HBconsumer.c: 0x1016 entries watched from the first heartbeat of that node on, in
//   pre-operational and operational; a time-out raises EMCY 0x8130 (CO_EMC_HEARTBEAT).
// - CiA 402: the power state machine (controlword commands, statusword bits 0-6, 9 remote,
//   11 internal limit active), 0x6060/0x6061 modes, 0x6071 target torque and 0x6072 max
//   torque in per mille of 0x6076, 0x6007 abort connection option code (the reaction to a
//   lost master: 0 none, 1 fault, 2 disable voltage, 3 quick stop), 0x60C2 interpolation time
//   period.
//
// - CiA 402 0x6064 position actual value: INTEGER32, in increments. A drive counts on past
//   2^31 - 1 to -2^31 (and back) - a multi-turn axis, a fine encoder, or an offset the drive
//   keeps (a homing): the count is the axis's position plus the offset, modulo 2^32 (RMP's note
//   "Signed 32-bit Motor Position Overflow/Underflow" describes the rollover masters see).
// - The DC link: statusword bit 4 (voltage enabled) is 1 while the power stage has its DC-link
//   voltage, in every state (SMC LECSN-T, statusword: bit 4 = 0 "the bus voltage is lower than
//   the certain level"). Until the DC link has charged after mains on, the drive stays in
//   switch on disabled: the shutdown command (transition 2) is not taken (KEB COMBIVERT F6
//   manual, CiA 402 state machine: "Switch on disabled is reached when ... the charging of the
//   DC link is not completed"); the drive acts on the shutdown command it holds once charged.
//
// Behaviours real drives have, switchable (Behaviour): TPDO COB-ID bit 30 required (no RTR:
// writing it 0 aborts 0x06090030; CANopenNode's own TPDO default is 0xC0000180 + node), a
// lag before 0x6061 shows a new mode, no 0x1006, a 0x60C2, its own 0x6072, no 0x6007, SYNC
// loss while enabled handled as a lost master (0x6007), an offset in 0x6064, and a DC link
// that charges some time after mains on (or mains that never come).
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <vector>

#include "reference/can/can_wire.h"
#include "reference/can/reference_plant.h"
#include "reference/can/reference_runner.h"

namespace hapticd::reference {

struct Cia402Behaviour {
  std::uint8_t node = 1;
  std::uint32_t rated_torque_mnm = 100;      // 0x6076
  std::uint16_t max_torque_permille = 3000;  // 0x6072; 0: the drive has no 0x6072
  bool tpdo_cob_id_bit30_required = false;
  int mode_display_lag_ms = 0;  // 0x6061 shows a new 0x6060 this much later
  bool has_1006 = true;
  bool has_60c2 = false;
  bool has_6007 = true;
  bool sync_loss_is_master_loss = true;  // SYNC time-out while enabled: the 0x6007 reaction
  // A limit of the drive's own that hapticd does not read (a current limit, a thermal
  // derating), per mille of 0x6076; 0: none. Limiting sets statusword bit 11.
  std::uint16_t internal_limit_permille = 0;
  // The axis: metres per 0x6064 increment, motor N m per axis newton.
  double metres_per_increment = 1e-5;
  double nm_per_newton = 0.01;
  // 0x6064 = the axis position in increments + this, modulo 2^32 (a signed 32-bit count).
  std::int64_t position_offset = 0;
  // Mains on at power-on (else when switch_mains_on() is called), and the DC link charged this
  // long after it; until then bit 4 is 0 and the drive stays in switch on disabled.
  bool mains_on_at_start = true;
  int dc_link_charge_ms = 0;
};

class Cia402Drive final : public ReferenceDevice {
 public:
  enum class Nmt : std::uint8_t { kPreOperational = 0x7F, kOperational = 0x05, kStopped = 0x04 };
  enum class Power : std::uint8_t {
    kSwitchOnDisabled,
    kReadyToSwitchOn,
    kSwitchedOn,
    kOperationEnabled,
    kQuickStopActive,
    kFault
  };

  Cia402Drive(const Cia402Behaviour& b, const PlantParameters& plant, std::int64_t now_ns);

  void on_frame(const Frame& f, std::int64_t now_ns, std::vector<Frame>& out) override;
  void on_clock(std::int64_t now_ns, std::vector<Frame>& out) override;

  // Any thread.
  Power power() const { return power_.load(); }
  bool torque_on() const { return power() == Power::kOperationEnabled; }
  double position_m() const { return plant_.position_now(); }
  double motor_force_n() const { return plant_.motor_force_now(); }
  // The hand starts pushing now (a test: once hapticd has output on).
  void press_now() { plant_.press_from(monotonic_ns()); }
  // Any thread: the drive faults at its next service (EMCY `code`, Fault).
  void inject_fault(std::uint16_t code) { injected_fault_.store(code); }
  // The test's: the next `n` RPDOs are lost on the way in (a receive FIFO overrun, a frame
  // the bus did not deliver), as CANopenNode never sees a frame its CAN driver dropped.
  void lose_rpdos(int n) { rpdos_to_lose_.store(n); }
  // Any thread: mains on now (the DC link charges dc_link_charge_ms from here).
  void switch_mains_on() { mains_on_ns_.store(monotonic_ns()); }
  // Any thread: shutdown commands the drive could not take for want of DC-link voltage.
  int dc_link_refusals() const { return dc_link_refusals_.load(); }
  // Any thread: the hand pushes with `newtons` from now on (after its press ramp).
  void set_hand_force(double newtons) { plant_.set_hand_force(newtons); }
  // The drive's thread, or after the runner stopped.
  std::uint32_t object(std::uint16_t index, std::uint8_t sub) const;
  bool has_object(std::uint16_t index, std::uint8_t sub) const;

 private:
  struct Entry {
    std::uint32_t value = 0;
    std::uint8_t size = 4;
    bool writable = false;
    bool rpdo = false;  // may be mapped into an RPDO / a TPDO
    bool tpdo = false;
  };
  struct Key {
    std::uint16_t index;
    std::uint8_t sub;
    bool operator<(const Key& o) const { return index != o.index ? index < o.index : sub < o.sub; }
  };
  struct PdoState {
    bool valid = false;
    std::uint8_t count = 0;  // mapped objects in force
  };

  // cia402_object_dictionary.cpp
  void build_dictionary();
  void add(std::uint16_t index, std::uint8_t sub, std::uint32_t value, std::uint8_t size,
           bool writable, bool rpdo = false, bool tpdo = false);
  void on_sdo(const Frame& f, std::int64_t now_ns, std::vector<Frame>& out);
  std::uint32_t write(Key k, std::uint32_t value, std::int64_t now_ns);  // abort code, 0: done
  std::uint32_t write_pdo_comm(Key k, std::uint32_t value);
  std::uint32_t write_pdo_mapping(Key k, std::uint32_t value);
  std::uint32_t read(Key k, std::uint32_t& value, std::uint8_t& size) const;
  PdoState& pdo(std::uint16_t comm_index);

  // cia402_drive.cpp
  void on_nmt(std::uint8_t command, std::vector<Frame>& out);
  void on_sync(std::int64_t now_ns, std::vector<Frame>& out);
  void on_rpdo(const Frame& f);
  void apply_controlword(std::uint16_t cw);
  void update_dc_link(std::int64_t now_ns);
  void set_power(Power p);
  void apply_torque();
  void lose_master(std::uint16_t emcy, std::vector<Frame>& out);
  void emcy(std::uint16_t code, std::vector<Frame>& out);
  std::uint16_t statusword() const;
  std::int32_t mapped(std::uint16_t index) const;

  Cia402Behaviour b_;
  ReferencePlant plant_;
  std::map<Key, Entry> od_;
  std::map<std::uint16_t, PdoState> pdos_;
  Nmt nmt_ = Nmt::kPreOperational;
  std::atomic<Power> power_{Power::kSwitchOnDisabled};
  std::uint16_t controlword_ = 0;
  std::int8_t mode_shown_ = 0;
  std::int64_t mode_shows_at_ns_ = 0;
  std::int8_t mode_pending_ = 0;
  bool limited_ = false;  // statusword bit 11: 0x6072 clamped the target torque
  // RPDO1 received since the last SYNC (synchronous: applied at it).
  bool rpdo_pending_ = false;
  Frame rpdo_frame_;
  std::uint64_t syncs_ = 0;
  // SYNC consumer (CO_SYNC.c): timer since the last SYNC, armed once one was seen.
  std::int64_t last_sync_ns_ = 0;
  int sync_timeout_state_ = 0;  // 0 not armed, 1 armed, 2 reported
  // Heartbeat consumer (CO_HBconsumer.c): 0 unknown, 1 active, 2 timed out.
  int hb_state_ = 0;
  std::int64_t hb_last_ns_ = 0;
  std::int64_t heartbeat_sent_ns_ = 0;
  std::uint16_t error_code_ = 0;
  std::atomic<std::uint16_t> injected_fault_{0};
  std::atomic<int> rpdos_to_lose_{0};
  // The DC link: mains on since (CLOCK_MONOTONIC; -1 off), charged, a shutdown held for it.
  std::atomic<std::int64_t> mains_on_ns_{-1};
  bool dc_link_charged_ = false;
  bool shutdown_held_ = false;
  std::atomic<int> dc_link_refusals_{0};
};

}  // namespace hapticd::reference
